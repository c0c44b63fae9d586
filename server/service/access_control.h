// Finds out who calls an RPC and whether they may; writes the audit log.
//
// Who (first match wins):
//   1. `authorization: Bearer <token>` metadata: the token's name and role.
//      A malformed, unknown or revoked token is UNAUTHENTICATED, even where
//      no token is needed: a credential that was sent is always checked.
//   2. With client certificates on (tls_client_ca), the verified
//      certificate's CN: a robot of that id. (Operators use tokens.)
//   3. Nobody: anonymous in the open mode, i.e. when auth is not required:
//      auth.required is false, there are no client certificates, and no
//      token was ever created in the database. Otherwise UNAUTHENTICATED.
// Audit rows are written for uploads, merges, deletes, token changes (in the
// same transaction as the change, by the handlers) and for refused writes
// (here, at most limits.audit_denials_per_minute rows per identity, the rest
// counted in summary rows: denial_audit.h). Calls without a valid credential
// are logged, never audited, so that strangers cannot fill the database.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_ACCESS_CONTROL_H_
#define MAPD_SERVICE_ACCESS_CONTROL_H_

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "common/status.h"
#include "service/auth.h"
#include "service/core.h"
#include "service/denial_audit.h"

namespace mapd::service {

struct AuthOptions {
  bool required = false;      // auth.required: no anonymous calls even without tokens
  bool client_certs = false;  // tls_client_ca is set: certificates identify robots
  // Denial rows per identity and minute (limits.audit_denials_per_minute),
  // shared by every AccessControl of one map (the gRPC and the web side);
  // null: one of their own at `denials_per_minute`.
  double denials_per_minute = 10;
  std::shared_ptr<DenialAuditLimiter> denials;
};

class AccessControl {
 public:
  AccessControl(Core* core, AuthOptions options);

  // Who is calling (see above): UNAUTHENTICATED naming what is missing or wrong.
  StatusOr<Principal> Authenticate(const grpc::ServerContextBase& context);

  // The same for a caller that is not a gRPC call (the web view): an HTTP
  // `Authorization` header's value (null: none sent), then the open mode.
  // No client certificates there. A header that is refused is logged with
  // `peer`, as a refused gRPC credential is (event=auth_refused).
  StatusOr<Principal> AuthenticateHeader(const std::string* authorization, const std::string& peer);

  // Authenticate, then Authorize(permission, robot). A refused write
  // (permission write, delete, merge, manage_tokens) is audited with
  // `target` (what the call would have acted on, e.g. "merge 7"; default
  // "robot <robot>").
  StatusOr<Principal> Admit(const grpc::ServerContextBase& context, Permission permission,
                            const std::string& action, const std::string& robot = "",
                            const std::string& target = "");

  // Authorize once the target is known (a submap's robot, a header's robot
  // id); a refusal is audited with `target`.
  Status Check(const Principal& principal, Permission permission, const std::string& action,
               const std::string& robot, const std::string& target);
  // AuthorizeMap: a token scoped to other maps is refused `map`, audited.
  Status CheckMap(const Principal& principal, const std::string& map, const std::string& action);
  // Check for the callback reactors, which must not block a gRPC thread on a
  // commit: `done` gets the verdict at once when it is OK (or not a write),
  // otherwise on the writer thread once the refusal's audit row is committed
  // (or has failed, which is logged like in Check).
  void CheckAsync(const Principal& principal, Permission permission, const std::string& action,
                  const std::string& robot, const std::string& target,
                  std::function<void(const Status&)> done);

  // True when a call without a credential is refused now; Unavailable when
  // the database cannot say (the caller is refused, and may retry).
  StatusOr<bool> Required();

  // An audit row stamped now, for a handler's own transaction.
  static storage::AuditEntry Entry(const Principal& principal, const std::string& action,
                                   const std::string& target, const std::string& result);
  // Appends `entry` in a transaction of its own, then runs `done` (on the writer thread).
  void AuditAsync(storage::AuditEntry entry, std::function<void()> done);
  // The same for a denial: written only if the identity's denial rows are
  // within limits.audit_denials_per_minute, otherwise counted (denial_audit.h).
  void AuditDeniedAsync(storage::AuditEntry entry, std::function<void()> done);
  // Writes the summary rows of counted denials that are due (mapd calls it
  // every second; `all` at shutdown).
  void FlushDenials(bool all = false);

 private:
  StatusOr<Principal> FromToken(std::string_view bearer);
  void AuditDenied(const Principal& principal, const std::string& action, const std::string& target,
                   const Status& why);
  static void LogDenied(const Principal& principal, const std::string& action,
                        const std::string& target);

  Core* const core_;
  const AuthOptions options_;
  const std::shared_ptr<DenialAuditLimiter> denials_;
  // Once a token exists it always does (rows are never deleted): cached.
  std::atomic<bool> tokens_exist_{false};
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_ACCESS_CONTROL_H_
