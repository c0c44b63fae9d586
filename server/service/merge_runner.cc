#include "service/merge_runner.h"

#include <chrono>
#include <condition_variable>
#include <memory>
#include <thread>
#include <utility>

#include "service/log.h"
#include "service/rpc_metrics.h"
#include "service/voxel_merge.h"

namespace mapd::service {
namespace {

void PublishPrepared(const PreparedSubmaps& prepared) {
  RpcMetrics::Default().SetPreparedSubmaps(prepared.size(), prepared.bytes());
}

}  // namespace

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
  // Freed on return, once the caller is woken: a campus pair's merged tree
  // takes ~0.15 s of this thread, which the caller spends storing the merge.
  std::shared_ptr<void> merged_tree;
  if (result.ok()) merged_tree = std::move(result->merged_tree);
  std::lock_guard<std::mutex> lock(mu_);
  if (!abandoned_) result_.emplace(std::move(result));
  cv_.notify_all();
}

struct MergeRunner::Preparation {
  PreparedKey key;
  std::string bytes;
  voxel::MergeParams params;
};

struct MergeRunner::State {
  State(size_t c, size_t q, size_t budget) : max_concurrent(c), max_queued(q), prepared(budget) {}
  const size_t max_concurrent;
  const size_t max_queued;
  PreparedSubmaps prepared;  // thread-safe itself
  mutable std::mutex mu;
  size_t running = 0;                                     // GUARDED_BY(mu)
  std::deque<std::shared_ptr<MergeJob>> queued;           // GUARDED_BY(mu)
  std::deque<std::unique_ptr<Preparation>> preparations;  // GUARDED_BY(mu)
  bool stopping = false;                                  // GUARDED_BY(mu)
  size_t preparing = 0;                                   // GUARDED_BY(mu)
  std::condition_variable prepared_cv;                    // preparing fell
  uint64_t next_owner = 1;                                // GUARDED_BY(mu)
};

MergeRunner::MergeRunner(size_t max_concurrent, size_t max_queued, size_t prepared_budget_bytes)
    : state_(std::make_shared<State>(max_concurrent, max_queued, prepared_budget_bytes)) {}

MergeRunner::~MergeRunner() {
  Shutdown();
  // Preparations are short (a second at most for a campus crop) and touch
  // the process's metrics: waited for, unlike merges, so that none outlives
  // the server.
  std::unique_lock<std::mutex> lock(state_->mu);
  state_->prepared_cv.wait(lock, [this] { return state_->preparing == 0; });
}

uint64_t MergeRunner::NewOwner() {
  std::lock_guard<std::mutex> lock(state_->mu);
  return state_->next_owner++;
}

void MergeRunner::CloseOwner(uint64_t owner) {
  state_->prepared.ForgetOwner(owner);
  PublishPrepared(state_->prepared);
}

void MergeRunner::Forget(uint64_t owner, uint64_t id) {
  state_->prepared.Forget({owner, id});
  PublishPrepared(state_->prepared);
}

StatusOr<std::shared_ptr<MergeJob>> MergeRunner::Submit(uint64_t owner, std::vector<uint64_t> ids,
                                                        std::vector<std::string> bytes,
                                                        const voxel::MergeParams& params) {
  if (!VoxelMergeBuilt()) return MergeVoxelSubmaps({}, params, {}).status();  // Unimplemented
  auto job = std::make_shared<MergeJob>();
  job->owner_ = owner;
  job->ids_ = std::move(ids);
  job->bytes_ = std::move(bytes);
  job->params_ = params;
  std::lock_guard<std::mutex> lock(state_->mu);
  if (state_->stopping) return Status::Unavailable("mapd is shutting down; merge not started");
  if (state_->running < state_->max_concurrent) {
    ++state_->running;
    std::thread(&MergeRunner::Work, state_, job, nullptr).detach();
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

void MergeRunner::PrepareAhead(uint64_t owner, uint64_t id, std::string bytes,
                               const voxel::MergeParams& params) {
  if (!VoxelMergeBuilt() || !state_->prepared.enabled()) return;
  auto preparation =
      std::make_unique<Preparation>(Preparation{{owner, id}, std::move(bytes), params});
  std::unique_ptr<Preparation> dropped;  // freed after the lock
  std::lock_guard<std::mutex> lock(state_->mu);
  if (state_->stopping) return;
  if (state_->running < state_->max_concurrent) {
    ++state_->running;
    ++state_->preparing;
    std::thread(&MergeRunner::Work, state_, nullptr, std::move(preparation)).detach();
    return;
  }
  if (state_->preparations.size() >= kMaxPreparations) {
    dropped = std::move(state_->preparations.front());
    state_->preparations.pop_front();
  }
  state_->preparations.push_back(std::move(preparation));
}

void MergeRunner::RunMerge(State* state, MergeJob* job) {
  std::vector<voxel::SubmapInput> inputs(job->ids_.size());
  for (size_t i = 0; i < inputs.size(); ++i) inputs[i] = {job->ids_[i], job->bytes_[i]};
  const auto progress = [job](const std::string& stage, double fraction) {
    job->Publish({stage, fraction});
  };
  if (!state->prepared.enabled()) {
    job->Finish(MergeVoxelSubmaps(inputs, job->params_, progress));
    return;
  }

  // The inputs' views: kept ones, and the others prepared now (and kept after).
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::shared_ptr<voxel::PreparedSubmap>> views(inputs.size());
  std::vector<voxel::SubmapInput> missing;
  std::vector<size_t> missing_at;
  for (size_t i = 0; i < inputs.size(); ++i) {
    views[i] = state->prepared.Take({job->owner_, inputs[i].id});
    if (views[i] == nullptr) {
      missing.push_back(inputs[i]);
      missing_at.push_back(i);
    }
  }
  StatusOr<voxel::MergeOutcome> result = Status::Internal("not merged");
  auto prepared = PrepareVoxelSubmaps(missing, job->params_);
  if (prepared.ok()) {
    for (size_t k = 0; k < missing_at.size(); ++k) views[missing_at[k]] = (*prepared)[k];
    const double reading_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result = MergePreparedVoxelSubmaps(views, job->params_, progress);
    if (result.ok()) {  // the inputs read here count as the merge's reading
      result->times.reading_s += reading_s;
      result->times.total_s += reading_s;
    }
  } else {
    result = prepared.status();
  }
  job->Finish(std::move(result));  // before the views go back: the caller waits
  for (size_t i = 0; i < inputs.size(); ++i) {
    state->prepared.Put({job->owner_, inputs[i].id}, std::move(views[i]));
  }
  PublishPrepared(state->prepared);
}

void MergeRunner::RunPreparation(State* state, const Preparation& preparation) {
  if (state->prepared.Has(preparation.key)) return;  // a merge read it meanwhile
  const auto start = std::chrono::steady_clock::now();
  auto views =
      PrepareVoxelSubmaps({{preparation.key.submap_id, preparation.bytes}}, preparation.params);
  if (!views.ok()) {  // the upload was checked; its merges will report this
    Log(LogLevel::kWarn, "submap_not_prepared",
        {{"submap", std::to_string(preparation.key.submap_id)},
         {"why", views.status().ToString()}});
    return;
  }
  Log(LogLevel::kDebug, "submap_prepared",
      {{"submap", std::to_string(preparation.key.submap_id)},
       {"s",
        std::to_string(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count())}});
  state->prepared.Put(preparation.key, std::move(views->front()));
  PublishPrepared(state->prepared);
}

void MergeRunner::Work(std::shared_ptr<State> state, std::shared_ptr<MergeJob> job,
                       std::unique_ptr<Preparation> preparation) {
  while (job != nullptr || preparation != nullptr) {
    if (job != nullptr && !job->abandoned()) {
      const auto start = std::chrono::steady_clock::now();
      RunMerge(state.get(), job.get());
      RpcMetrics::Default().RecordMerge(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    } else if (preparation != nullptr) {
      RunPreparation(state.get(), *preparation);
      std::lock_guard<std::mutex> lock(state->mu);
      --state->preparing;
      state->prepared_cv.notify_all();
    }
    job.reset();
    preparation.reset();
    std::lock_guard<std::mutex> lock(state->mu);
    if (state->stopping) {
      --state->running;
    } else if (!state->queued.empty()) {       // merges first: someone waits for them
      job = std::move(state->queued.front());  // this thread keeps its slot
      state->queued.pop_front();
    } else if (!state->preparations.empty()) {
      preparation = std::move(state->preparations.front());
      state->preparations.pop_front();
      ++state->preparing;
    } else {
      --state->running;
    }
  }
}

void MergeRunner::Shutdown() {
  std::deque<std::shared_ptr<MergeJob>> dropped;
  std::deque<std::unique_ptr<Preparation>> not_prepared;
  {
    std::lock_guard<std::mutex> lock(state_->mu);
    state_->stopping = true;
    dropped.swap(state_->queued);
    not_prepared.swap(state_->preparations);
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
