// Whether the database takes writes. The writer records the storage outcome
// of every commit attempt; while commits fail (disk full, read-only, I/O
// error, a lock held too long by another process) the server reports
// NOT_SERVING with the reason, refuses batches and writes at once instead of
// queueing them, and retries with a growing pause. The first commit that
// succeeds again (a batch or a probe) makes it healthy, except after a full
// disk, which only the probe declares over (see Record).
//
// Thread safety: every method may be called from any thread; the listener
// runs on the thread that recorded the change, without internal locks held.
#ifndef MAPD_SERVICE_WRITE_HEALTH_H_
#define MAPD_SERVICE_WRITE_HEALTH_H_

#include <chrono>
#include <functional>
#include <mutex>

#include "common/status.h"

namespace mapd::service {

class WriteHealth {
 public:
  // Runs on every change between healthy (Ok) and failing (the failure).
  void SetListener(std::function<void(const Status&)> listener);

  // What an outcome comes from.
  enum class Attempt {
    kCommit,  // a batch group or a write job
    kProbe,   // the writer's probe (Store::ProbeWrite)
  };
  // An attempt's outcome. Only storage failures count (see
  // IsStorageFailure); anything else is a verdict on the request. A success
  // clears a failure, except a full disk (ResourceExhausted), which only a
  // probe clears: the probe asks for real room, while a retried commit can
  // fit in the space its failed attempt freed and the next batch fail again
  // (health flapped between NOT_SERVING and SERVING on a full tmpfs).
  void Record(const Status& outcome, Attempt attempt = Attempt::kCommit);

  bool ok() const;
  // Ok, or Unavailable with the failure's reason and what to do.
  Status status() const;
  // The pause before the next attempt while failing: 50 ms, doubling per
  // failure, at most 1 s.
  std::chrono::milliseconds Backoff() const;

  // Disk full, I/O errors, read-only files, locks held past the timeout.
  static bool IsStorageFailure(const Status& s);

 private:
  mutable std::mutex mu_;
  Status failure_;                               // GUARDED_BY(mu_)
  int consecutive_ = 0;                          // GUARDED_BY(mu_), failures in a row
  std::function<void(const Status&)> listener_;  // GUARDED_BY(mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_WRITE_HEALTH_H_
