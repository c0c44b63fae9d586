// Identities and the audit log: the stored side of server/service/auth.h.
// One intent of storage::Store (storage/store.h).
#ifndef MAPD_STORAGE_AUTH_STORE_H_
#define MAPD_STORAGE_AUTH_STORE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"

namespace mapd::storage {

// A token as stored: never its secret, only the secret's SHA-256.
struct TokenRecord {
  int64_t id = 0;
  std::string name;           // unique, chosen by whoever created it
  std::string role;           // reader / robot / operator / admin (server/service/auth.h)
  std::string robot_id;       // robot tokens: the robot they write for
  std::string secret_sha256;  // 32 bytes
  int64_t created_ns = 0;
  std::string created_by;  // the creator's name ("mapd token create" offline)
  int64_t revoked_ns = 0;  // 0 while valid
  std::string maps;        // the maps it may act on, comma-separated; empty = every map
};

struct AuditEntry {
  int64_t id = 0;
  int64_t time_ns = 0;
  std::string who;  // token name or certificate CN
  std::string role;
  std::string action;      // the RPC, e.g. "UploadSubmap"
  std::string target;      // what it acted on, e.g. "robot r1 submap 'room'"
  std::string result;      // "ok", "denied: ...", or the error
  std::string peer;        // the caller's address as gRPC or HTTP gives it ('' offline)
  std::string credential;  // "token", "certificate", "none" (open mode), "database file"
};

// Reads of tokens and the audit log. Any thread.
class AuthReader {
 public:
  virtual ~AuthReader() = default;
  // Tokens: by id (NotFound), all of them by id, and whether any was ever made.
  virtual StatusOr<TokenRecord> GetToken(int64_t id) = 0;
  virtual StatusOr<std::vector<TokenRecord>> ListTokens() = 0;
  virtual StatusOr<bool> AnyTokenEver() = 0;
  // The newest `limit` audit entries, newest first.
  virtual StatusOr<std::vector<AuditEntry>> ListAudit(int limit) = 0;
};

// Writes of tokens and audit rows, in a WriteTransaction (storage/store.h).
class AuthWriter {
 public:
  virtual ~AuthWriter() = default;
  // Stores a new token (id filled in by the store); AlreadyExists for a taken name.
  virtual StatusOr<int64_t> InsertToken(const TokenRecord& token) = 0;
  // Marks a token revoked; NotFound if there is none, FailedPrecondition if
  // it is revoked already.
  virtual Status RevokeToken(int64_t id, int64_t now_ns) = 0;
  // Control characters in `entry`'s fields are stored escaped (one line each).
  virtual Status AppendAudit(const AuditEntry& entry) = 0;
  // Deletes the oldest rows of refused calls (result "denied...") beyond the
  // newest `keep`; returns how many. Other rows are never deleted.
  virtual StatusOr<int64_t> TrimDeniedAudit(int64_t keep) = 0;
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_AUTH_STORE_H_
