// GlobalMapBuilder: keeps the stored global map (storage::GlobalMapRecord)
// the union of every submap whose place in the map frame is known.
//
// Members: every upload (never a merged output) that is in a session whose
// frame is tied, at that tie (T_map_frame), or else that an accepted merge
// placed (storage::SubmapPlacement). A change (an accepted merge, an upload,
// a delete) calls Invalidate(); one worker thread then works out the members
// and either fuses the new ones into the stored map (incremental: every old
// member still there at the same pose, none finer than the map) or rebuilds
// the map from its members in the order they first joined
// (voxel/global_map.h). Each stored change gets the next version. Builds are
// coalesced: several changes during a build make one more build.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_GLOBAL_MAP_BUILDER_H_
#define MAPD_SERVICE_GLOBAL_MAP_BUILDER_H_

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

#include "common/status.h"
#include "service/core.h"
#include "voxel/occupancy_fusion.h"

namespace mapd::service {

class GlobalMapBuilder {
 public:
  // Starts the worker, which builds once the core is ready (a database
  // upgraded from a version without the global map table gets its first).
  GlobalMapBuilder(Core* core, voxel::FusionParams params);
  ~GlobalMapBuilder();  // Stop()
  GlobalMapBuilder(const GlobalMapBuilder&) = delete;
  GlobalMapBuilder& operator=(const GlobalMapBuilder&) = delete;

  // Something that may change the members was committed: build again.
  void Invalidate();
  // Waits up to `timeout` until every Invalidate() before this call has been
  // built (or has failed); true if so.
  bool WaitUntilCurrent(std::chrono::milliseconds timeout);
  // Why the last build failed (empty: it did not).
  std::string last_error() const;
  // Ends the worker. A build in progress is abandoned after the fusion of
  // its current member and stores nothing; the next start builds again.
  void Stop();

 private:
  void Loop();
  // One build: works out the members, fuses, stores. Ok when nothing changed.
  Status BuildOnce();

  Core* const core_;
  const voxel::FusionParams params_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  uint64_t requested_ = 1;  // GUARDED_BY(mu_): Invalidate() calls, plus the start
  uint64_t built_ = 0;      // GUARDED_BY(mu_): requests covered by a finished build
  // Set under mu_ (so the waits on cv_ see it), read without it by a build
  // in progress.
  std::atomic<bool> stop_{false};
  bool backfilled_ = false;  // GUARDED_BY(mu_): old merges' placements recorded
  std::string last_error_;   // GUARDED_BY(mu_)
  std::thread worker_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_GLOBAL_MAP_BUILDER_H_
