#include "service/watch_hub.h"

#include <algorithm>
#include <string>
#include <thread>

namespace mapd::service {
namespace {

// About 50 MB of features at most (a FusedView with its robots is a few
// hundred bytes); a client behind more than this gets a resync.
constexpr size_t kMaxHistoryEntries = 256 * 1024;

size_t Entries(const MapChange& c) {
  return c.lines.size() + c.lines_gone.size() + c.planes.size() + c.planes_gone.size();
}

}  // namespace

Watcher::Next Watcher::Take(std::chrono::duration<double> timeout, ChangePtr* change) {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait_for(lock, timeout, [this] { return closed_ || behind_ || !queue_.empty(); });
  if (closed_) return Next::kClosed;
  if (behind_) {
    behind_ = false;
    return Next::kBehind;
  }
  if (queue_.empty()) return Next::kTimeout;
  *change = std::move(queue_.front());
  queue_.pop_front();
  return Next::kChange;
}

void Watcher::SetWriting(bool writing) {
  std::lock_guard<std::mutex> lock(mu_);
  writing_ = writing;
}

bool Watcher::behind() const {
  std::lock_guard<std::mutex> lock(mu_);
  return behind_;
}

bool Watcher::closed() const {
  std::lock_guard<std::mutex> lock(mu_);
  return closed_;
}

void WatchHub::Start(uint64_t version) {
  std::lock_guard<std::mutex> lock(mu_);
  started_ = true;
  version_ = version;
  floor_ = version;
  history_.clear();
  history_entries_ = 0;
}

bool WatchHub::wanted() const {
  std::lock_guard<std::mutex> lock(mu_);
  return options_.history > 0 || !watchers_.empty();
}

uint64_t WatchHub::version() const {
  std::lock_guard<std::mutex> lock(mu_);
  return version_;
}

void WatchHub::Publish(ChangePtr change) {
  std::lock_guard<std::mutex> lock(mu_);
  if (!started_ || change->to_version <= version_) return;
  if (change->empty()) {
    // Nothing to send; the history stays contiguous (a gap means "no
    // change"), so a client at any version in it still resumes.
    version_ = change->to_version;
    if (history_.empty()) floor_ = version_;
    return;
  }
  version_ = change->to_version;
  if (options_.history > 0) {
    history_.push_back(change);
    history_entries_ += Entries(*change);
    // At most `history` changes, and at most kMaxHistoryEntries features,
    // planes and ids in all: a round that touched the whole map (a merge
    // approved, a rebuild) must not let history hold many copies of it.
    while (history_.size() > options_.history ||
           (history_.size() > 1 && history_entries_ > kMaxHistoryEntries)) {
      floor_ = history_.front()->to_version;
      history_entries_ -= Entries(*history_.front());
      history_.pop_front();
    }
  } else {
    floor_ = version_;
  }
  for (const std::shared_ptr<Watcher>& w : watchers_) {
    std::lock_guard<std::mutex> wlock(w->mu_);
    if (w->closed_ || w->behind_) continue;  // a resync is due anyway
    if (w->queue_.size() >= w->capacity_) {
      // Never more than `queue` changes per watcher: drop them, resync later.
      w->queue_.clear();
      w->behind_ = true;
    } else {
      w->queue_.push_back(change);
    }
    w->cv_.notify_one();
  }
}

StatusOr<WatchHub::Subscription> WatchHub::Subscribe(uint64_t since_version,
                                                     std::function<void()> cancel) {
  std::lock_guard<std::mutex> lock(mu_);
  if (closed_) return Status::Unavailable("mapd is shutting down; watch again after it restarts");
  if (!started_) return Status::Unavailable("mapd is recovering its fused map; retry in a moment");
  if (watchers_.size() >= options_.max_watchers) {
    return Status::ResourceExhausted(
        "WatchFeatureMap: " + std::to_string(watchers_.size()) +
        " watches are open, the most limits.max_watchers allows; retry later");
  }
  Subscription sub;
  sub.watcher =
      std::shared_ptr<Watcher>(new Watcher(std::max<size_t>(1, options_.queue), std::move(cancel)));
  if (since_version > 0 && since_version >= floor_) {
    sub.resync = false;
    for (const ChangePtr& c : history_) {
      if (c->to_version > since_version) sub.replay.push_back(c);
    }
  }
  watchers_.push_back(sub.watcher);
  return sub;
}

void WatchHub::Unsubscribe(const std::shared_ptr<Watcher>& watcher) {
  std::lock_guard<std::mutex> lock(mu_);
  watchers_.erase(std::remove(watchers_.begin(), watchers_.end(), watcher), watchers_.end());
}

void WatchHub::Close() {
  bool writing = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    closed_ = true;
    for (const std::shared_ptr<Watcher>& w : watchers_) {
      std::lock_guard<std::mutex> wlock(w->mu_);
      w->closed_ = true;
      w->queue_.clear();
      w->cv_.notify_one();
      writing = writing || w->writing_;
    }
  }
  // A write to a client that reads ends within microseconds; one still in
  // progress after kWriteGrace is blocked on a client that does not read,
  // and would hold the shutdown up: cancel it (that client gets CANCELLED,
  // the others UNAVAILABLE with the version to resume from).
  constexpr auto kWriteGrace = std::chrono::milliseconds(100);
  const auto deadline = std::chrono::steady_clock::now() + kWriteGrace;
  while (writing && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    std::lock_guard<std::mutex> lock(mu_);
    writing = std::any_of(watchers_.begin(), watchers_.end(), [](const auto& w) {
      std::lock_guard<std::mutex> wlock(w->mu_);
      return w->writing_;
    });
  }
  std::lock_guard<std::mutex> lock(mu_);
  for (const std::shared_ptr<Watcher>& w : watchers_) {
    std::lock_guard<std::mutex> wlock(w->mu_);
    if (w->writing_ && w->cancel_) w->cancel_();
  }
}

size_t WatchHub::watchers() const {
  std::lock_guard<std::mutex> lock(mu_);
  return watchers_.size();
}

}  // namespace mapd::service
