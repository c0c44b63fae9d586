#include "service/merge_runner.h"

#include <chrono>
#include <thread>
#include <utility>

#include "service/log.h"
#include "service/rpc_metrics.h"
#include "service/voxel_merge.h"

namespace mapd::service {

bool MergeJob::Wait(std::chrono::milliseconds timeout, std::vector<MergeProgressEvent>* events) {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait_for(lock, timeout, [this] { return !events_.empty() || result_.has_value(); });
  for (MergeProgressEvent& e : events_) events->push_back(std::move(e));
  events_.clear();
  return result_.has_value();
}

StatusOr<voxel::MergeOutcome> MergeJob::TakeResult() {
  std::lock_guard<std::mutex> lock(mu_);
  StatusOr<voxel::MergeOutcome> r = std::move(*result_);
  result_.reset();
  return r;
}

void MergeJob::Abandon() {
  std::lock_guard<std::mutex> lock(mu_);
  abandoned_ = true;
}

bool MergeJob::abandoned() {
  std::lock_guard<std::mutex> lock(mu_);
  return abandoned_;
}

void MergeJob::Publish(MergeProgressEvent event) {
  std::lock_guard<std::mutex> lock(mu_);
  if (abandoned_) return;
  events_.push_back(std::move(event));
  cv_.notify_all();
}

void MergeJob::Finish(StatusOr<voxel::MergeOutcome> result) {
  std::lock_guard<std::mutex> lock(mu_);
  if (!abandoned_) result_.emplace(std::move(result));
  cv_.notify_all();
}

struct MergeRunner::State {
  State(size_t c, size_t q) : max_concurrent(c), max_queued(q) {}
  const size_t max_concurrent;
  const size_t max_queued;
  mutable std::mutex mu;
  size_t running = 0;                            // GUARDED_BY(mu)
  std::deque<std::shared_ptr<MergeJob>> queued;  // GUARDED_BY(mu)
  bool stopping = false;                         // GUARDED_BY(mu)
};

MergeRunner::MergeRunner(size_t max_concurrent, size_t max_queued)
    : state_(std::make_shared<State>(max_concurrent, max_queued)) {}

MergeRunner::~MergeRunner() { Shutdown(); }

StatusOr<std::shared_ptr<MergeJob>> MergeRunner::Submit(std::vector<uint64_t> ids,
                                                        std::vector<std::string> bytes,
                                                        const voxel::MergeParams& params) {
  if (!VoxelMergeBuilt()) return MergeVoxelSubmaps({}, params, {}).status();  // Unimplemented
  auto job = std::make_shared<MergeJob>();
  job->ids_ = std::move(ids);
  job->bytes_ = std::move(bytes);
  job->params_ = params;
  std::lock_guard<std::mutex> lock(state_->mu);
  if (state_->stopping) return Status::Unavailable("mapd is shutting down; merge not started");
  if (state_->running < state_->max_concurrent) {
    ++state_->running;
    std::thread(&MergeRunner::Work, state_, job).detach();
    return job;
  }
  if (state_->queued.size() < state_->max_queued) {
    state_->queued.push_back(job);
    return job;
  }
  return Status::ResourceExhausted(
      std::to_string(state_->running) + " merges are running and " +
      std::to_string(state_->queued.size()) +
      " are waiting (limits.max_concurrent_merges = " + std::to_string(state_->max_concurrent) +
      ", limits.max_queued_merges = " + std::to_string(state_->max_queued) + "); retry later");
}

void MergeRunner::Work(std::shared_ptr<State> state, std::shared_ptr<MergeJob> job) {
  while (job) {
    if (!job->abandoned()) {
      std::vector<voxel::SubmapInput> inputs(job->ids_.size());
      for (size_t i = 0; i < inputs.size(); ++i) inputs[i] = {job->ids_[i], job->bytes_[i]};
      MergeJob* j = job.get();
      const auto start = std::chrono::steady_clock::now();
      StatusOr<voxel::MergeOutcome> result =
          MergeVoxelSubmaps(inputs, job->params_, [j](const std::string& stage, double fraction) {
            j->Publish({stage, fraction});
          });
      RpcMetrics::Default().RecordMerge(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      job->Finish(std::move(result));
    }
    job.reset();
    std::lock_guard<std::mutex> lock(state->mu);
    if (!state->stopping && !state->queued.empty()) {
      job = std::move(state->queued.front());  // this thread keeps its slot
      state->queued.pop_front();
    } else {
      --state->running;
    }
  }
}

void MergeRunner::Shutdown() {
  std::deque<std::shared_ptr<MergeJob>> dropped;
  {
    std::lock_guard<std::mutex> lock(state_->mu);
    state_->stopping = true;
    dropped.swap(state_->queued);
  }
  for (const auto& job : dropped) {
    job->Finish(Status::Unavailable(
        "mapd is shutting down; the merge was not started, nothing was stored"));
  }
}

size_t MergeRunner::running() const {
  std::lock_guard<std::mutex> lock(state_->mu);
  return state_->running;
}

}  // namespace mapd::service
