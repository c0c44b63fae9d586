// Bearer tokens: `mapd_<id>_<secret>`, the secret 32 random bytes from
// OpenSSL's CSPRNG in base64url (43 characters). Only SHA-256(secret) is
// stored; a presented token is checked by looking its id up and comparing
// hashes in constant time. The id is not secret: it only says which row to
// compare with.
#ifndef MAPD_SERVICE_TOKEN_H_
#define MAPD_SERVICE_TOKEN_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "service/auth.h"
#include "storage/store.h"

namespace mapd::service {

// 32 bytes of SHA-256.
std::string Sha256(std::string_view data);
// a == b without a data-dependent early exit (CRYPTO_memcmp).
bool ConstantTimeEqual(std::string_view a, std::string_view b);

// Splits `mapd_<id>_<secret>`; InvalidArgument (naming the expected form) otherwise.
Status ParseToken(std::string_view token, int64_t* id, std::string* secret);

// Token names and robot ids: 1-128 characters of [A-Za-z0-9_.-].
bool ValidTokenName(const std::string& name);

struct NewToken {
  std::string name;
  Role role = Role::kReader;
  std::string robot_id;  // required for Role::kRobot, refused otherwise
  std::string created_by;
  std::vector<std::string> maps;  // map ids it may act on; empty = every map
};

struct IssuedToken {
  storage::TokenRecord record;
  std::string token;  // the full secret token: shown once, never stored
};

// Checks `t`, draws a secret and inserts the hashed token in `txn`. The one
// way tokens are made, by `mapd token create` and by the CreateToken RPC.
StatusOr<IssuedToken> IssueToken(const NewToken& t, int64_t now_ns, storage::WriteTransaction* txn);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_TOKEN_H_
