// A Core (server/service/core.h) whose state a test sets: readiness, the
// published features, the fusion backlog, what becomes of a batch. Stored rows
// come from a real Store on a temporary database. Handlers run on it exactly
// as on MapCore, so a test reaches states the real core shows only under
// load or faults (recovery, a refusing disk, a backlog) without causing them.
#ifndef MAPD_TESTS_SERVICE_FAKE_CORE_H_
#define MAPD_TESTS_SERVICE_FAKE_CORE_H_

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "common/temp_dir.h"
#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/core.h"
#include "service/map_service.h"
#include "service/watch_hub.h"
#include "storage/sqlite/store.h"

namespace mapd::testing {

class FakeCore final : public service::Core {
 public:
  explicit FakeCore(service::WatchOptions watch = {}) : hub_(watch) {
    auto store = storage::SqliteStore::Open(dir_.File("map.db"), {});
    EXPECT_TRUE(store.ok()) << store.status().ToString();
    if (store.ok()) store_ = std::move(store).value();
    hub_.Start(map_version);
  }

  // Readiness (CheckReady): settable while the service runs, since its
  // threads (the global map builder) ask at any time.
  void SetReady(Status ready) {
    std::lock_guard<std::mutex> lock(mu_);
    ready_ = std::move(ready);
  }

  // What the test sets (before the handlers run).
  std::vector<service::FusedView> features;
  uint64_t map_version = 1;
  uint64_t backlog = 0;
  service::BatchOutcome outcome{service::BatchOutcome::Kind::kStored, Status::Ok()};

  // What the handlers did.
  size_t submitted() const {
    std::lock_guard<std::mutex> lock(mu_);
    return submitted_;
  }

  Status CheckReady() const override {
    std::lock_guard<std::mutex> lock(mu_);
    ++check_ready_calls_;
    return ready_;
  }
  size_t check_ready_calls() const {
    std::lock_guard<std::mutex> lock(mu_);
    return check_ready_calls_;
  }
  void Submit(service::IngestBatch, service::DoneCallback done) override {
    {
      std::lock_guard<std::mutex> lock(mu_);
      ++submitted_;
    }
    done(outcome);
  }
  Status ExecuteWrite(service::WriteFunction write) override {
    if (Status ready = CheckReady(); !ready.ok()) return ready;
    std::lock_guard<std::mutex> lock(write_mu_);  // one writer, as in MapCore
    StatusOr<std::unique_ptr<storage::WriteTransaction>> txn = store_->BeginWrite();
    if (!txn.ok()) return txn.status();
    MAPD_RETURN_IF_ERROR(write(txn->get()));
    return (*txn)->Commit();
  }
  void SubmitWrite(service::WriteFunction write, std::function<void(const Status&)> done) override {
    done(ExecuteWrite(std::move(write)));
  }
  std::vector<service::FusedView> QueryFeatures(const service::FeatureQuery&, uint64_t* version,
                                                std::vector<service::PlaneView>*) const override {
    *version = map_version;
    return features;
  }
  uint64_t FusionBacklog() const override { return backlog; }
  service::CoreStats Stats() const override {
    service::CoreStats stats;
    stats.fused_features = features.size();
    stats.fusion_backlog = backlog;
    stats.map_version = map_version;
    return stats;
  }
  storage::Store& store() override { return *store_; }
  // A test publishes changes into it as the fuser would.
  service::WatchHub& watch_hub() override { return hub_; }

 private:
  TempDir dir_;
  std::unique_ptr<storage::Store> store_;
  mutable std::mutex mu_;
  std::mutex write_mu_;
  size_t submitted_ = 0;
  Status ready_ = Status::Ok();           // guarded by mu_
  mutable size_t check_ready_calls_ = 0;  // guarded by mu_
  service::WatchHub hub_;
};

// The gRPC handlers (MapServiceImpl) on a core, served on a loopback port,
// and a stub to call them; drained and shut down when destroyed.
class ServedCore {
 public:
  explicit ServedCore(service::Core* core)
      : service_(std::make_unique<service::MapServiceImpl>(core, service::IngestOptions{})) {
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(service_.get());
    server_ = builder.BuildAndStart();
    EXPECT_NE(server_, nullptr) << "cannot serve the handlers on a loopback port";
    stub_ = mapserver::v1::MapService::NewStub(grpc::CreateChannel(
        "127.0.0.1:" + std::to_string(port), grpc::InsecureChannelCredentials()));
  }
  ~ServedCore() {
    service_->StartDraining();
    if (server_) server_->Shutdown();
  }

  mapserver::v1::MapService::Stub* stub() const { return stub_.get(); }

 private:
  std::unique_ptr<service::MapServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<mapserver::v1::MapService::Stub> stub_;
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_SERVICE_FAKE_CORE_H_
