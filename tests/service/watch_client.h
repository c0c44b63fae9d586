// A WatchFeatureMap client for tests: reads the stream on a thread of its
// own and keeps the map the deltas describe, as a real client would.
#ifndef MAPD_TESTS_SERVICE_WATCH_CLIENT_H_
#define MAPD_TESTS_SERVICE_WATCH_CLIENT_H_

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::testing {

class WatchClient {
 public:
  // Opens the call at once; with read = false nothing is read until Read().
  // A non-empty `token` is sent as the call's bearer token.
  WatchClient(mapserver::v1::MapService::Stub* stub,
              const mapserver::v1::WatchFeatureMapRequest& request, bool read = true,
              const std::string& token = "") {
    if (!token.empty()) ctx_.AddMetadata("authorization", "Bearer " + token);
    reader_ = stub->WatchFeatureMap(&ctx_, request);
    if (read) Read();
  }
  ~WatchClient() {
    Cancel();
    if (thread_.joinable()) thread_.join();
  }

  void Read() {
    thread_ = std::thread([this] {
      mapserver::v1::FeatureMapDelta m;
      while (reader_->Read(&m)) {
        std::lock_guard<std::mutex> lock(mu_);
        Apply(m);
        messages_.push_back(m);
        cv_.notify_all();
      }
      grpc::Status s = reader_->Finish();
      std::lock_guard<std::mutex> lock(mu_);
      status_ = s;
      done_ = true;
      cv_.notify_all();
    });
  }
  void Cancel() { ctx_.TryCancel(); }

  // Waits (bounded, so a bug fails instead of hanging) until `pred` holds,
  // checked under the client's lock after every message.
  bool WaitFor(const std::function<bool()>& pred,
               std::chrono::seconds bound = std::chrono::seconds(60)) {
    std::unique_lock<std::mutex> lock(mu_);
    return cv_.wait_for(lock, bound, [&] { return pred(); });
  }
  bool WaitForVersion(uint64_t version) {
    return WaitFor([&] { return version_ >= version || done_; }) && version_ >= version;
  }
  // The stream's status once it ended.
  grpc::Status Finish() {
    WaitFor([&] { return done_; });
    if (thread_.joinable()) thread_.join();
    return status_;
  }

  // Read under the lock (WaitFor's predicate) or after Finish().
  std::vector<mapserver::v1::FeatureMapDelta> messages_;
  std::map<uint64_t, mapserver::v1::FusedFeature> features_;
  std::map<uint64_t, mapserver::v1::FusedPlane> planes_;
  uint64_t version_ = 0;  // of the last message with more = false
  bool done_ = false;
  std::mutex mu_;

  std::vector<mapserver::v1::FeatureMapDelta> Messages() {
    std::lock_guard<std::mutex> lock(mu_);
    return messages_;
  }
  std::map<uint64_t, mapserver::v1::FusedFeature> Features() {
    std::lock_guard<std::mutex> lock(mu_);
    return features_;
  }
  uint64_t Version() {
    std::lock_guard<std::mutex> lock(mu_);
    return version_;
  }

 private:
  void Apply(const mapserver::v1::FeatureMapDelta& m) {
    if (m.resync()) {
      features_.clear();
      planes_.clear();
    }
    for (const auto& f : m.added()) features_[f.id()] = f;
    for (const auto& f : m.updated()) features_[f.id()] = f;
    for (uint64_t id : m.removed()) features_.erase(id);
    for (const auto& p : m.added_planes()) planes_[p.id()] = p;
    for (const auto& p : m.updated_planes()) planes_[p.id()] = p;
    for (uint64_t id : m.removed_planes()) planes_.erase(id);
    if (!m.more()) version_ = m.map_version();
  }

  grpc::ClientContext ctx_;
  std::unique_ptr<grpc::ClientReader<mapserver::v1::FeatureMapDelta>> reader_;
  std::condition_variable cv_;
  grpc::Status status_;
  std::thread thread_;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_SERVICE_WATCH_CLIENT_H_
