#include "service/denial_audit.h"

#include <algorithm>

namespace mapd::service {
namespace {

// "1,250": the figure an operator reads in `mapctl audit`.
std::string Grouped(uint64_t n) {
  std::string digits = std::to_string(n), out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
    out += digits[i];
  }
  return out;
}

}  // namespace

void DenialAuditLimiter::Refill(Identity* id, int64_t now_ns) const {
  const double minutes = static_cast<double>(now_ns - id->refilled_ns) / 60e9;
  id->tokens = std::min(per_minute_, id->tokens + std::max(0.0, minutes) * per_minute_);
  id->refilled_ns = now_ns;
}

bool DenialAuditLimiter::Admit(const storage::AuditEntry& entry, int64_t now_ns) {
  std::lock_guard<std::mutex> lock(mu_);
  auto [it, added] = identities_.try_emplace({entry.who, entry.role});
  Identity& id = it->second;
  if (added) {
    id.tokens = per_minute_;  // a full bucket: the first denials are all recorded
    id.refilled_ns = now_ns;
  }
  Refill(&id, now_ns);
  // Pending summaries go first (TakeSummaries), so that rows stay in order.
  if (id.tokens >= 1 && id.suppressed.empty()) {
    id.tokens -= 1;
    return true;
  }
  ++id.suppressed[entry.action];
  return false;
}

std::vector<storage::AuditEntry> DenialAuditLimiter::TakeSummaries(int64_t now_ns, bool all) {
  std::vector<storage::AuditEntry> rows;
  std::lock_guard<std::mutex> lock(mu_);
  for (auto it = identities_.begin(); it != identities_.end();) {
    Identity& id = it->second;
    Refill(&id, now_ns);
    if (!id.suppressed.empty() && (all || id.tokens >= 1)) {
      id.tokens = std::max(0.0, id.tokens - 1);
      const auto& [who, role] = it->first;
      for (const auto& [action, n] : id.suppressed) {
        storage::AuditEntry e;
        e.time_ns = now_ns;
        e.who = who;
        e.role = role;
        e.action = action;
        e.result = "denied: " + Grouped(n) + " more denial" + (n == 1 ? "" : "s");
        e.result += " of " + action;
        e.result += " by " + who;
        e.result += " (not recorded one by one: limits.audit_denials_per_minute)";
        rows.push_back(std::move(e));
      }
      id.suppressed.clear();
    }
    // An identity with a full bucket and nothing pending is forgotten: the
    // map holds only identities refused in the last minute or so.
    if (id.suppressed.empty() && id.tokens >= per_minute_) {
      it = identities_.erase(it);
    } else {
      ++it;
    }
  }
  return rows;
}

}  // namespace mapd::service
