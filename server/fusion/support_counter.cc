#include "fusion/support_counter.h"

#include <algorithm>
#include <iterator>
#include <utility>

namespace mapd::fusion {

void SupportCounter::Add(ObservationId id, uint32_t cap) {
  if (!exact()) {
    if (id != last_) ++count_;
  } else if (ids_.empty() || id > ids_.back()) {
    ids_.push_back(id);  // the common case: observations arrive in id order
  } else if (auto it = std::lower_bound(ids_.begin(), ids_.end(), id);
             it == ids_.end() || *it != id) {
    ids_.insert(it, id);
  }
  last_ = id;
  SaturateAbove(cap);
}

void SupportCounter::Merge(SupportCounter&& other, uint32_t cap) {
  // Union into the longer list: take other's when it is longer.
  if (exact() && other.exact() && ids_.size() < other.ids_.size()) ids_.swap(other.ids_);
  Merge(static_cast<const SupportCounter&>(other), cap);
}

void SupportCounter::Merge(const SupportCounter& other, uint32_t cap) {
  if (exact() && other.exact()) {
    // The sorted union of both id lists.
    const std::vector<ObservationId>& more = other.ids_;
    if (more.empty()) {
    } else if (ids_.empty() || more.front() > ids_.back()) {
      ids_.insert(ids_.end(), more.begin(), more.end());
    } else if (more.back() < ids_.front()) {
      ids_.insert(ids_.begin(), more.begin(), more.end());
    } else {
      std::vector<ObservationId> both;
      both.reserve(ids_.size() + more.size());
      std::set_union(ids_.begin(), ids_.end(), more.begin(), more.end(), std::back_inserter(both));
      ids_ = std::move(both);
    }
  } else {
    const uint32_t shared = last_ == other.last_ ? 1 : 0;
    count_ = count() + other.count() - shared;
    std::vector<ObservationId>().swap(ids_);
  }
  last_ = std::max(last_, other.last_);
  SaturateAbove(cap);
}

void SupportCounter::SaturateAbove(uint32_t cap) {
  if (!exact() || ids_.size() <= cap) return;
  count_ = static_cast<uint32_t>(ids_.size());
  std::vector<ObservationId>().swap(ids_);  // gives the memory back
}

SupportCounter SupportCounter::FromState(std::vector<ObservationId> ids, uint32_t count,
                                         ObservationId last) {
  SupportCounter c;
  c.ids_ = std::move(ids);
  c.count_ = count;
  c.last_ = last;
  return c;
}

}  // namespace mapd::fusion
