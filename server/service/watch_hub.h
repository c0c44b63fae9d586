// WatchHub: the change feed of the fused map behind WatchFeatureMap.
//
// The fuser publishes one MapChange per round (the features and planes whose
// published state changed, read from the engines at the round's end) and
// never waits for a watcher: Publish() appends the change to a bounded
// history (for clients that reconnect) and to each watcher's bounded queue.
// A watcher whose queue is full is marked behind and its queue dropped; the
// handler then sends it the full filtered map (a resync) once it reads again.
// So a slow reader costs at most `queue` changes of memory and nothing of
// ingest.
//
// Versions are the core's map_version (observations reflected). A change
// covers (from_version, to_version]; consecutive changes are contiguous
// (rounds that changed nothing published only move the version on).
//
// Thread safety: every method may be called from any thread. Lock order:
// the hub's mutex, then a watcher's.
#ifndef MAPD_SERVICE_WATCH_HUB_H_
#define MAPD_SERVICE_WATCH_HUB_H_

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "common/status.h"
#include "service/core.h"
#include "service/options.h"

namespace mapd::service {

// What one round of the fuser changed in the published map. States are as of
// to_version.
struct MapChange {
  uint64_t from_version = 0;
  uint64_t to_version = 0;
  std::vector<FusedView> lines;                // changed and published
  std::vector<fusion::ClusterId> lines_gone;   // published before, not now
  std::vector<PlaneView> planes;               // the same for planes
  std::vector<fusion::ClusterId> planes_gone;  //
  bool empty() const {
    return lines.empty() && lines_gone.empty() && planes.empty() && planes_gone.empty();
  }
};
using ChangePtr = std::shared_ptr<const MapChange>;

// One open watch: its queue of changes. Made by WatchHub::Subscribe.
class Watcher {
 public:
  enum class Next {
    kChange,   // *change is the next one
    kBehind,   // the queue overflowed (now empty): send a resync
    kClosed,   // the hub closed (shutdown): end the stream
    kTimeout,  // nothing yet
  };
  // Takes the next change, waiting at most `timeout` for one.
  Next Take(std::chrono::duration<double> timeout, ChangePtr* change);
  // Brackets a write to the client: WatchHub::Close() cancels the call
  // (`cancel` given to Subscribe) only while one is in progress, since
  // a blocked write would otherwise hold the shutdown up.
  void SetWriting(bool writing);
  bool behind() const;
  bool closed() const;

 private:
  friend class WatchHub;
  explicit Watcher(size_t capacity, std::function<void()> cancel)
      : capacity_(capacity), cancel_(std::move(cancel)) {}
  const size_t capacity_;
  const std::function<void()> cancel_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::deque<ChangePtr> queue_;  // GUARDED_BY(mu_)
  bool behind_ = false;          // GUARDED_BY(mu_)
  bool closed_ = false;          // GUARDED_BY(mu_)
  bool writing_ = false;         // GUARDED_BY(mu_)
};

class WatchHub {
 public:
  explicit WatchHub(const WatchOptions& options) : options_(options) {}

  // The map is at `version` and nothing before it is kept (at start, once
  // the fused map is recovered). Until then Subscribe is refused.
  void Start(uint64_t version);
  // Whether a change is wanted at all (someone watches or history is kept):
  // lets the fuser skip building it.
  bool wanted() const;
  // The fuser: the map moved from version() to change->to_version. `change`
  // may be empty (nothing published changed): only the version moves.
  void Publish(ChangePtr change);
  uint64_t version() const;

  struct Subscription {
    std::shared_ptr<Watcher> watcher;
    // since_version > 0 and the history covers it: the changes after it,
    // oldest first (the watcher's queue has the ones after these).
    std::vector<ChangePtr> replay;
    // The client must get the full filtered map first: since_version is 0,
    // or older than the history (a restart, or more than `history` changes).
    bool resync = true;
  };
  // Opens a watch. `cancel` ends its call (see Watcher::SetWriting); it is
  // never called after Unsubscribe returns. ResourceExhausted beyond
  // max_watchers, Unavailable before Start or after Close.
  StatusOr<Subscription> Subscribe(uint64_t since_version, std::function<void()> cancel);
  void Unsubscribe(const std::shared_ptr<Watcher>& watcher);
  // Shutdown: every watcher gets kClosed, new watches are refused; a write
  // still in progress 100 ms later (a client that does not read) is
  // cancelled. Returns after that.
  void Close();
  size_t watchers() const;

 private:
  const WatchOptions options_;
  mutable std::mutex mu_;
  bool started_ = false;           // GUARDED_BY(mu_)
  bool closed_ = false;            // GUARDED_BY(mu_)
  uint64_t version_ = 0;           // GUARDED_BY(mu_)
  uint64_t floor_ = 0;             // GUARDED_BY(mu_): history holds every change after this
  std::deque<ChangePtr> history_;  // GUARDED_BY(mu_)
  size_t history_entries_ = 0;     // GUARDED_BY(mu_): features, planes and ids in history_
  std::vector<std::shared_ptr<Watcher>> watchers_;  // GUARDED_BY(mu_)
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_WATCH_HUB_H_
