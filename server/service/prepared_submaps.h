// PreparedSubmaps: the submaps mapd has read and viewed for merging
// (voxel::PreparedSubmap), kept for the next merges of them, within a memory
// budget (merge.prepared_submaps_mib), least recently used first out.
//
// Why: a merge spends 0.5-0.7 s of one core on each campus-sized input alone
// (reading the octree, its voxel grid, levelling it), and an operator merges
// a submap with several others; MergeRunner prepares each upload ahead, in a
// free merge slot, so that a merge starts from the views
// (docs/voxel-merge.md, "Prepared submaps").
//
// A view is used by one merge at a time: Take() hands it out and removes it,
// Put() brings it back. Views are keyed by the map's owner token (each
// SubmapService has its own, with its own merge parameters, so a view is
// only ever merged with the parameters it was prepared with) and submap id.
//
// Thread safety: every method may be called from any thread. Views are
// freed outside the lock (a campus view takes ~0.1 s to free).
#ifndef MAPD_SERVICE_PREPARED_SUBMAPS_H_
#define MAPD_SERVICE_PREPARED_SUBMAPS_H_

#include <cstddef>
#include <cstdint>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <utility>
#include <vector>

#include "voxel/merge.h"  // types only

namespace mapd::service {

struct PreparedKey {
  uint64_t owner = 0;  // MergeRunner::NewOwner()
  uint64_t submap_id = 0;
  bool operator<(const PreparedKey& o) const {
    return std::pair(owner, submap_id) < std::pair(o.owner, o.submap_id);
  }
};

class PreparedSubmaps {
 public:
  using View = std::shared_ptr<voxel::PreparedSubmap>;

  explicit PreparedSubmaps(std::size_t budget_bytes) : budget_bytes_(budget_bytes) {}

  bool enabled() const { return budget_bytes_ > 0; }

  // The view of `key`, removed until Put() brings it back; null when there
  // is none.
  View Take(const PreparedKey& key);
  // Keeps `view` (taken, or new) unless its submap was forgotten since it was
  // taken, its owner is gone, or it alone exceeds the budget; then frees the
  // least recently used views beyond the budget.
  void Put(const PreparedKey& key, View view);
  // True when `key` has a view, in the cache or taken.
  bool Has(const PreparedKey& key) const;
  // The submap is deleted (or its owner closed): its view goes, now or
  // when it is put back.
  void Forget(const PreparedKey& key);
  void ForgetOwner(uint64_t owner);

  std::size_t bytes() const;  // held by the views in the cache (not taken ones)
  std::size_t size() const;   // views in the cache

 private:
  struct Entry {
    View view;
    std::size_t bytes = 0;
    std::list<PreparedKey>::iterator lru;
  };
  // Removes `key` from entries_ and lru_, adding its view to *freed.
  void EraseLocked(std::map<PreparedKey, Entry>::iterator it, std::vector<View>* freed);

  const std::size_t budget_bytes_;
  mutable std::mutex mu_;
  std::map<PreparedKey, Entry> entries_;  // GUARDED_BY(mu_)
  std::list<PreparedKey> lru_;            // GUARDED_BY(mu_), most recent first
  std::set<PreparedKey> taken_;           // GUARDED_BY(mu_)
  std::set<PreparedKey> forgotten_;       // GUARDED_BY(mu_), taken ones to drop on Put
  std::set<uint64_t> closed_owners_;      // GUARDED_BY(mu_)
  std::size_t bytes_ = 0;                 // GUARDED_BY(mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_PREPARED_SUBMAPS_H_
