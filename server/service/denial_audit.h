// How many refused calls reach the audit log (issue 43: a reader token
// added 500 rows in 0.16 s and pushed real entries out of `mapctl audit`).
//
// Per identity (token name or certificate CN, with its role), a token
// bucket: `per_minute` denial rows a minute, and as many at once. Denials
// beyond it are counted per action and written later as one row each,
//   who=Y action=X result="denied: 1,250 more denials of X by Y (not
//   recorded one by one: limits.audit_denials_per_minute)"
// when the identity may write a row again (TakeSummaries, every second).
// Allowed privileged actions never pass through here: they are always
// recorded, in the transaction of their change. Denial rows are also capped
// in the database (limits.audit_max_denied_rows, WriteTransaction::
// TrimDeniedAudit), so that a flood cannot grow it without bound.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_DENIAL_AUDIT_H_
#define MAPD_SERVICE_DENIAL_AUDIT_H_

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "storage/store.h"

namespace mapd::service {

class DenialAuditLimiter {
 public:
  explicit DenialAuditLimiter(double per_minute) : per_minute_(per_minute) {}

  // True when the denial `entry` may be written now (it takes a token);
  // otherwise it is counted for a summary row.
  bool Admit(const storage::AuditEntry& entry, int64_t now_ns);

  // The summary rows of identities that may write a row again (each takes
  // a token), or of every identity when `all` (at shutdown).
  std::vector<storage::AuditEntry> TakeSummaries(int64_t now_ns, bool all = false);

 private:
  struct Identity {
    double tokens = 0;
    int64_t refilled_ns = 0;
    std::map<std::string, uint64_t> suppressed;  // by action
  };
  void Refill(Identity* id, int64_t now_ns) const;

  const double per_minute_;
  std::mutex mu_;
  std::map<std::pair<std::string, std::string>, Identity> identities_;  // (who, role)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_DENIAL_AUDIT_H_
