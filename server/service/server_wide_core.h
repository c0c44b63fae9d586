// ServerWideCore: the Core (core.h) of what belongs to the server rather
// than to a map, when maps live in a shared PostgreSQL database and this
// mapd may serve none of them: tokens, WhoAmI, the denial counts and the
// audit rows of server-wide calls (CreateMap, token management).
//
// With a local store those live in the default map's database and its
// MapCore; on PostgreSQL the default map may be served by another instance,
// so every instance has one of these, over the default map's store opened
// without its lease (the writer then refuses map data).
//
// Writes run one at a time on a worker thread of their own. There is no
// fused map: Submit refuses batches, QueryFeatures answers none.
#ifndef MAPD_SERVICE_SERVER_WIDE_CORE_H_
#define MAPD_SERVICE_SERVER_WIDE_CORE_H_

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "service/core.h"
#include "service/watch_hub.h"

namespace mapd::service {

class ServerWideCore final : public Core {
 public:
  explicit ServerWideCore(std::unique_ptr<storage::Store> store);
  // Runs the writes queued so far, then joins the worker.
  ~ServerWideCore() override;

  Status CheckReady() const override { return Status::Ok(); }
  void Submit(IngestBatch batch, DoneCallback done) override;
  Status ExecuteWrite(WriteFunction write) override;
  void SubmitWrite(WriteFunction write, std::function<void(const Status&)> done) override;
  std::vector<FusedView> QueryFeatures(const FeatureQuery& query, uint64_t* map_version,
                                       std::vector<PlaneView>* planes) const override;
  uint64_t FusionBacklog() const override { return 0; }
  CoreStats Stats() const override { return {}; }
  storage::Store& store() override { return *store_; }
  WatchHub& watch_hub() override { return watch_hub_; }

 private:
  struct Job {
    WriteFunction write;
    std::function<void(const Status&)> done;
  };
  Status RunWrite(const WriteFunction& write);  // on the worker
  void WorkerLoop();

  std::unique_ptr<storage::Store> store_;
  WatchHub watch_hub_{WatchOptions{}};
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;  // GUARDED_BY(mu_)
  bool stop_ = false;     // GUARDED_BY(mu_)
  std::thread worker_;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_SERVER_WIDE_CORE_H_
