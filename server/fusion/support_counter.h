// The support of a cluster: how many distinct observations its members came
// from (feature-fusion paper, Li et al. 2023, section 3.2: a cluster is
// published once it was seen often enough; docs/algorithms.md A.6).
#ifndef MAPD_FUSION_SUPPORT_COUNTER_H_
#define MAPD_FUSION_SUPPORT_COUNTER_H_

#include <cstdint>
#include <limits>
#include <vector>

namespace mapd::fusion {

using ObservationId = uint64_t;  // unique per observation batch, assigned by the caller

// Exact while at most `cap` distinct observations were counted: the ids are
// kept. Past the cap the ids are dropped (memory stays bounded whatever the
// history) and only a count goes on:
//  - Add() counts an observation unless it is the one added last (features of
//    one observation arrive together, so this is exact for a growing cluster);
//  - Merge() adds the two counts, less one when both last saw the same
//    observation. An observation that saw two pieces of a wall before they
//    merged is then counted twice: support past the cap may overcount.
// The exact engine uses an unlimited cap; the bounded engine a cap well above
// min_support, so publication never depends on the approximation.
class SupportCounter {
 public:
  static constexpr uint32_t kUnlimited = std::numeric_limits<uint32_t>::max();

  void Add(ObservationId id, uint32_t cap);
  // Absorbs `other` (left in an unspecified state).
  void Merge(SupportCounter&& other, uint32_t cap);
  // The same count and state as Merge(copy of other), without the copy: a
  // wall merges its pieces' counters on every refit (WallConsolidator::WallsOf).
  void Merge(const SupportCounter& other, uint32_t cap);

  uint32_t count() const { return exact() ? static_cast<uint32_t>(ids_.size()) : count_; }
  bool exact() const { return count_ == 0; }
  ObservationId last() const { return last_; }

  // State for snapshots (engine_state.cc): the ids while exact, else empty.
  const std::vector<ObservationId>& ids() const { return ids_; }
  static SupportCounter FromState(std::vector<ObservationId> ids, uint32_t count,
                                  ObservationId last);
  uint32_t saturated_count() const { return count_; }

 private:
  void SaturateAbove(uint32_t cap);

  std::vector<ObservationId> ids_;  // ascending, distinct; empty once saturated
  uint32_t count_ = 0;              // 0 while exact, else the (approximate) count
  ObservationId last_ = 0;          // most recently added (Merge: the larger of both)
};

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_SUPPORT_COUNTER_H_
