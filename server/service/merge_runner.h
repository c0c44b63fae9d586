// MergeRunner: computes submap merges off the RPC threads, with a concurrency
// limit and a bounded wait queue.
//
// A merge may take seconds and voxel::MergeSubmaps cannot be interrupted
// (it stops itself after MergeParams::max_seconds). So a job owns copies of
// its inputs and runs on a detached worker thread that shares nothing with the
// server but the runner's own reference-counted state: a handler whose client
// went away, or a server that shuts down, abandons the job and returns at
// once; the worker finishes in the background and its result is dropped.
// Abandoned jobs keep their slot until their computation ends, so the limit
// on concurrent merges holds for CPU and memory, not only for RPCs.
//
// Storing results is the handler's business (on its own thread, through
// MapCore), never the worker's: nothing is written after an abandon.
//
// Prepared submaps (prepared_submaps.h): with a budget, the runner keeps the
// views merges read of their inputs, and prepares uploads ahead
// (PrepareAhead) in a free slot when no merge waits, so that a merge starts
// from its inputs' views. A merge's decision does not depend on it: the same
// views are computed the same way, earlier.
//
// Thread safety: every method may be called from any thread.
#ifndef MAPD_SERVICE_MERGE_RUNNER_H_
#define MAPD_SERVICE_MERGE_RUNNER_H_

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"
#include "service/prepared_submaps.h"
#include "voxel/merge.h"

namespace mapd::service {

struct MergeProgressEvent {
  std::string stage;    // "corners", "matching", "alignment", "fusion"
  double fraction = 0;  // [0, 1] of the whole merge
};

// One merge, shared by the handler that waits for it and the worker.
class MergeJob {
 public:
  // Waits up to `timeout` for news; moves the progress events since the last
  // call into *events. True once the result is there (TakeResult()).
  bool Wait(std::chrono::milliseconds timeout, std::vector<MergeProgressEvent>* events);
  // REQUIRES: Wait() returned true. Once.
  StatusOr<voxel::MergeOutcome> TakeResult();
  // The handler gives up: the job is skipped if it has not started, and its
  // result is dropped when it ends.
  void Abandon();

 private:
  friend class MergeRunner;
  void Publish(MergeProgressEvent event);
  // Hands the result over, then frees its merged tree on the calling thread.
  void Finish(StatusOr<voxel::MergeOutcome> result);
  bool abandoned();

  uint64_t owner_ = 0;
  std::vector<uint64_t> ids_;
  std::vector<std::string> bytes_;
  voxel::MergeParams params_;

  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<MergeProgressEvent> events_;                // GUARDED_BY(mu_)
  std::optional<StatusOr<voxel::MergeOutcome>> result_;  // GUARDED_BY(mu_)
  bool abandoned_ = false;                               // GUARDED_BY(mu_)
};

class MergeRunner {
 public:
  // prepared_budget_bytes: memory for prepared submaps (0: none; every
  // merge reads its inputs, as without the runner's help).
  MergeRunner(size_t max_concurrent, size_t max_queued, size_t prepared_budget_bytes = 0);
  ~MergeRunner();  // Shutdown()

  // A token for one map's submaps (submap ids are per map; so are merge
  // parameters): the owner of the views prepared for it. Never reused.
  uint64_t NewOwner();
  // The map is closing: its views are freed and none is kept after.
  void CloseOwner(uint64_t owner);

  // Starts the merge of `owner`'s submaps `ids` now, or queues it behind the
  // running ones. Unimplemented when mapd was built without voxel merging;
  // ResourceExhausted when max_concurrent run and max_queued wait already;
  // Unavailable after Shutdown().
  StatusOr<std::shared_ptr<MergeJob>> Submit(uint64_t owner, std::vector<uint64_t> ids,
                                             std::vector<std::string> bytes,
                                             const voxel::MergeParams& params);

  // Prepares submap `id` for merging (an upload), when a slot is free and no
  // merge waits; with `params`, which must be those its merges will use. No-op
  // without a budget or the voxel library. At most kMaxPreparations wait; the
  // oldest is dropped beyond (its merges read it themselves).
  void PrepareAhead(uint64_t owner, uint64_t id, std::string bytes,
                    const voxel::MergeParams& params);
  static constexpr size_t kMaxPreparations = 32;
  // Submap `id` is deleted: its view is freed.
  void Forget(uint64_t owner, uint64_t id);

  // Refuses new jobs; queued ones end with Unavailable; running ones finish
  // in the background and are dropped. Does not wait for them.
  void Shutdown();

  size_t running() const;  // computations in progress, abandoned ones included

 private:
  struct State;
  struct Preparation;
  // Runs `job` or `preparation`, then what waits (merges first) on this slot.
  static void Work(std::shared_ptr<State> state, std::shared_ptr<MergeJob> job,
                   std::unique_ptr<Preparation> preparation);
  // Merges and finishes `job`; its inputs' views are kept after.
  static void RunMerge(State* state, MergeJob* job);
  static void RunPreparation(State* state, const Preparation& preparation);
  std::shared_ptr<State> state_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_MERGE_RUNNER_H_
