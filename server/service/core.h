// Core: what the gRPC handlers need of mapd's state, as an interface.
// MapCore (map_core.h) is the implementation: the database, the fusion
// engines and their threads. The handlers (map_service, submap_service,
// auth_service, access_control, the ingest and upload reactors) see only
// this, so a test can give them a fake (tests/service/fake_core.h) to reach
// states the real core reaches only by accident: recovery, a full disk, a
// fusion backlog, a refused batch.
//
// Reads of stored rows (submaps, tokens, robots, audit) go through store():
// the storage library is the contract there, and a fake serves them from a
// real Store on a temporary database.
//
// Thread safety: implementations are safe to call from any thread.
#ifndef MAPD_SERVICE_CORE_H_
#define MAPD_SERVICE_CORE_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "common/status.h"
#include "fusion/engine.h"
#include "fusion/plane_engine.h"
#include "geometry/box2.h"
#include "service/ingest_batch.h"
#include "service/latency_histogram.h"
#include "storage/store.h"

namespace mapd::service {

class WatchHub;  // watch_hub.h

struct BatchOutcome {
  enum class Kind { kStored, kDuplicate, kRejected };
  Kind kind = Kind::kRejected;
  Status status;  // why, when kRejected
};
using DoneCallback = std::function<void(const BatchOutcome&)>;

enum class KindFilter { kAny = 0, kLine = 1, kPlane = 2 };

struct FeatureQuery {
  std::optional<geometry::Box2> bbox;  // only features whose segment meets the box
  uint32_t min_support = 0;            // raised to the fusion min_support
  KindFilter kind = KindFilter::kAny;
  // How long to wait for the fuser to reflect every acknowledged batch;
  // < 0: MapCoreOptions::max_query_wait_s.
  double max_wait_s = -1;
};

// A published fused feature, ready for the API.
struct FusedView {
  fusion::FusedFeature feature;
  KindFilter kind = KindFilter::kLine;  // kPlane when a member came from a plane
  std::vector<std::string> robots;      // names, sorted
};

// A published fused non-vertical plane, ready for the API.
struct PlaneView {
  fusion::FusedPlane plane;
  std::vector<std::string> robots;  // names, sorted
};

struct CoreStats {
  uint64_t batches_stored = 0;  // by this process since it started
  uint64_t features_stored = 0;
  double batches_per_s = 0;  // over the last 10 s
  double features_per_s = 0;
  uint64_t fused_features = 0;
  uint64_t clusters = 0;
  uint64_t retired_walls = 0;  // seen through since last seen (fusion.retire_views)
  uint64_t map_version = 0;
  uint64_t fusion_backlog = 0;  // committed observations not fused yet
  uint64_t commits = 0;         // group commits by this process
  double uptime_s = 0;
  bool recovering = false;          // the fused map is being rebuilt at start
  bool replaying = false;           // serving, still replaying what followed the snapshot
  double snapshot_age_s = 0;        // newest snapshot of the fusion state (0: none)
  uint64_t replay_length = 0;       // observations fused since that snapshot
  uint64_t fused_raw_features = 0;  // raw features in the engine (folded ones included)
  uint64_t fusion_nodes = 0;        // the engine's nodes (representatives in bounded mode)
  uint64_t fused_planes = 0;        // published non-vertical planes
  uint64_t plane_nodes = 0;         // the plane engine's nodes
  std::string write_failure;        // why the database refuses writes now; empty: it takes them
  HistogramSnapshot ack_latency;    // Submit to acknowledgement of stored batches, seconds
  // Batches refused because their robot kept the fuser busy (fusion_share.h),
  // and the robots with observations waiting for fusion or refusals.
  uint64_t fusion_share_refused = 0;
  struct RobotShare {
    std::string robot;
    uint64_t pending = 0;         // observations committed, not fused
    double cost_per_obs_s = 0.0;  // the fuser's recent CPU per observation
    uint64_t refused = 0;
  };
  std::vector<RobotShare> fusion_shares;
};

using WriteFunction = std::function<Status(storage::WriteTransaction*)>;

class Core {
 public:
  virtual ~Core() = default;

  // Ok once the fused map is recovered; else Unavailable saying how far
  // recovery is. Batches and writes are refused until then.
  virtual Status CheckReady() const = 0;

  // Queues a validated batch; `done` runs once it is committed (durable),
  // found to be a duplicate, or refused.
  virtual void Submit(IngestBatch batch, DoneCallback done) = 0;
  // Runs `write` in a transaction of its own on the one writer and returns
  // its outcome (write's error or the commit's).
  virtual Status ExecuteWrite(WriteFunction write) = 0;
  // The same without waiting: `done` gets the outcome.
  virtual void SubmitWrite(WriteFunction write, std::function<void(const Status&)> done) = 0;

  // The published lines and, if `planes` is not null, planes (one snapshot).
  virtual std::vector<FusedView> QueryFeatures(const FeatureQuery& query, uint64_t* map_version,
                                               std::vector<PlaneView>* planes = nullptr) const = 0;
  // Acknowledged observations the fuser has not reflected yet.
  virtual uint64_t FusionBacklog() const = 0;
  virtual CoreStats Stats() const = 0;
  // Stored rows, read-only use by the handlers (writes go through ExecuteWrite).
  virtual storage::Store& store() = 0;
  // The change feed of the published map (WatchFeatureMap); the fuser
  // publishes into it, a watch subscribes.
  virtual WatchHub& watch_hub() = 0;
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_CORE_H_
