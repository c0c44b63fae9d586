// A server-sent-events reader over httplib's client, on a thread of its
// own: the test takes parsed events one by one.
#ifndef MAPD_TESTS_WEB_SSE_CLIENT_H_
#define MAPD_TESTS_WEB_SSE_CLIENT_H_

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "web/http.h"

namespace mapd::testing {

struct SseEvent {
  std::string id, type, data;
};

class SseClient {
 public:
  SseClient(int port, httplib::Headers headers, const std::string& path = "/api/events")
      : client_("127.0.0.1", port) {
    client_.set_read_timeout(60);
    thread_ = std::thread([this, headers, path] {
      httplib::Result r = client_.Get(
          path.c_str(), headers,
          [this](const httplib::Response& res) {
            status_ = res.status;
            return true;
          },
          [this](const char* data, size_t n) {
            Parse(std::string(data, n));
            return !stop_.load();
          });
      std::lock_guard<std::mutex> lock(mu_);
      ended_ = true;
      cv_.notify_all();
    });
  }
  ~SseClient() {
    stop_ = true;
    client_.stop();
    thread_.join();
  }

  // The next event, or nothing if none came within `timeout` (or the stream ended).
  std::optional<SseEvent> Next(std::chrono::seconds timeout = std::chrono::seconds(30)) {
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait_for(lock, timeout, [this] { return !events_.empty() || ended_; });
    if (events_.empty()) return std::nullopt;
    SseEvent e = events_.front();
    events_.pop_front();
    return e;
  }
  int status() const { return status_; }

 private:
  void Parse(const std::string& chunk) {
    std::lock_guard<std::mutex> lock(mu_);
    buffer_ += chunk;
    size_t end;
    while ((end = buffer_.find("\n\n")) != std::string::npos) {
      SseEvent e;
      size_t at = 0;
      const std::string block = buffer_.substr(0, end);
      while (at < block.size()) {
        size_t nl = block.find('\n', at);
        if (nl == std::string::npos) nl = block.size();
        const std::string line = block.substr(at, nl - at);
        if (line.rfind("id: ", 0) == 0) e.id = line.substr(4);
        if (line.rfind("event: ", 0) == 0) e.type = line.substr(7);
        if (line.rfind("data: ", 0) == 0) e.data += line.substr(6);
        at = nl + 1;
      }
      buffer_.erase(0, end + 2);
      if (!e.type.empty()) events_.push_back(e);
    }
    cv_.notify_all();
  }

  httplib::Client client_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> status_{0};
  std::mutex mu_;
  std::condition_variable cv_;
  std::string buffer_;
  std::deque<SseEvent> events_;
  bool ended_ = false;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_WEB_SSE_CLIENT_H_
