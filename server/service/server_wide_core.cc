#include "service/server_wide_core.h"

#include <future>

namespace mapd::service {

ServerWideCore::ServerWideCore(std::unique_ptr<storage::Store> store)
    : store_(std::move(store)), worker_([this] { WorkerLoop(); }) {}

ServerWideCore::~ServerWideCore() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  worker_.join();
}

void ServerWideCore::Submit(IngestBatch, DoneCallback done) {
  BatchOutcome refused;
  refused.status =
      Status::FailedPrecondition("batches go to a map's own service, not the server's");
  done(refused);
}

Status ServerWideCore::ExecuteWrite(WriteFunction write) {
  std::promise<Status> outcome;
  std::future<Status> result = outcome.get_future();
  SubmitWrite(std::move(write), [&outcome](const Status& s) { outcome.set_value(s); });
  return result.get();
}

void ServerWideCore::SubmitWrite(WriteFunction write, std::function<void(const Status&)> done) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!stop_) {
      jobs_.push_back({std::move(write), std::move(done)});
      cv_.notify_one();
      return;
    }
  }
  done(Status::Unavailable("mapd is shutting down"));
}

std::vector<FusedView> ServerWideCore::QueryFeatures(const FeatureQuery&, uint64_t* map_version,
                                                     std::vector<PlaneView>*) const {
  if (map_version != nullptr) *map_version = 0;
  return {};
}

Status ServerWideCore::RunWrite(const WriteFunction& write) {
  StatusOr<std::unique_ptr<storage::WriteTransaction>> txn = store_->BeginWrite();
  if (!txn.ok()) {
    // PostgreSQL restarted or the network failed: connect again, once.
    if (txn.status().code() != StatusCode::kUnavailable || !store_->ProbeWrite().ok()) {
      return txn.status();
    }
    txn = store_->BeginWrite();
    if (!txn.ok()) return txn.status();
  }
  MAPD_RETURN_IF_ERROR(write(txn->get()));
  return (*txn)->Commit();
}

void ServerWideCore::WorkerLoop() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
      if (jobs_.empty()) return;  // stopping, and nothing left
      job = std::move(jobs_.front());
      jobs_.pop_front();
    }
    job.done(RunWrite(job.write));
  }
}

}  // namespace mapd::service
