#include "service/delayed_calls.h"

#include <pthread.h>

#include <utility>
#include <vector>

namespace mapd::service {

DelayedCalls::DelayedCalls() {
  thread_ = std::thread([this] {
    pthread_setname_np(pthread_self(), "mapd-delayed");
    Loop();
  });
}

DelayedCalls::~DelayedCalls() { Stop(); }

void DelayedCalls::Post(std::chrono::steady_clock::duration delay, std::function<void()> fn) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!stopping_) {
      calls_.emplace(std::chrono::steady_clock::now() + delay, std::move(fn));
      cv_.notify_one();
      return;
    }
  }
  fn();
}

void DelayedCalls::Stop() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
    cv_.notify_one();
  }
  if (thread_.joinable()) thread_.join();
}

void DelayedCalls::Loop() {
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    if (stopping_) break;
    if (calls_.empty()) {
      cv_.wait(lock);
      continue;
    }
    const auto first = calls_.begin()->first;
    if (std::chrono::steady_clock::now() < first) {
      cv_.wait_until(lock, first);
      continue;
    }
    std::function<void()> fn = std::move(calls_.begin()->second);
    calls_.erase(calls_.begin());
    lock.unlock();
    fn();  // without the lock: it may Post again
    lock.lock();
  }
  // Stopping: everything still waiting runs now, in deadline order.
  std::vector<std::function<void()>> rest;
  for (auto& [deadline, fn] : calls_) rest.push_back(std::move(fn));
  calls_.clear();
  lock.unlock();
  for (std::function<void()>& fn : rest) fn();
}

}  // namespace mapd::service
