// PlaneFusionEngine snapshots (plane_engine.h: SaveState / LoadState).
//
// Layout, little-endian, doubles as their IEEE bits so that a restored engine
// continues bit for bit:
//   "MAPDPLN1" | u32 version | params key | counters | nodes | u64 FNV-1a of all before
//   node: id, observation, normal, offset, boundary, parent, size, root stats.
// Derived data (node centroids, the grid, cluster ids, the published planes)
// is recomputed from these, the grid in node order as the live engine filed it.
#include <cstring>
#include <string>

#include "fusion/plane_engine_impl.h"
#include "fusion/state_codec.h"

namespace mapd::fusion {
namespace {

constexpr char kPlaneMagic[8] = {'M', 'A', 'P', 'D', 'P', 'L', 'N', '1'};
constexpr uint32_t kPlaneVersion = 1;

class PlaneWriter : public StateWriter {
 public:
  using StateWriter::StateWriter;
  void V3(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) F64(v(i));
  }
  void Points(const std::vector<Eigen::Vector3d>& p) {
    U64(p.size());
    for (const Eigen::Vector3d& x : p) V3(x);
  }
};

class PlaneReader : public StateReader {
 public:
  using StateReader::StateReader;
  Eigen::Vector3d V3() {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) v(i) = F64();
    return v;
  }
  std::vector<Eigen::Vector3d> Points() {
    std::vector<Eigen::Vector3d> p(Count(24));
    for (Eigen::Vector3d& x : p) x = V3();
    return p;
  }
};

Status PlaneCorrupt(const std::string& what) {
  return Status::InvalidArgument("plane fusion snapshot is corrupt: " + what);
}

}  // namespace

Status PlaneFusionEngine::SaveState(std::string* out) const {
  const Impl& e = *impl_;
  out->clear();
  out->append(kPlaneMagic, sizeof(kPlaneMagic));
  PlaneWriter w(out);
  w.U32(kPlaneVersion);
  w.Str(PlaneFusionParamsKey(e.params_));
  w.U64(e.cluster_count_);
  w.U64(e.plane_count_);
  w.U64(e.nodes_.size());
  for (size_t i = 0; i < e.nodes_.size(); ++i) {
    const PlaneNode& n = e.nodes_[i];
    w.U64(n.id);
    w.U64(n.observation);
    w.V3(n.normal);
    w.F64(n.offset_m);
    w.Points(n.boundary);
    w.U32(e.parent_[i]);
    w.U32(e.size_[i]);
    w.Raw<uint8_t>(e.stats_[i] ? 1 : 0);
    if (!e.stats_[i]) continue;
    const PlaneStats& s = *e.stats_[i];
    w.U64(s.id);
    w.U32(s.member_count);
    w.U64(s.point_count);
    w.V3(s.mean);
    for (int k = 0; k < 9; ++k) w.F64(s.scatter(k));
    w.V3(s.normal_sum);
    w.Points(s.hull);
    w.Ids(s.observations.ids());
    w.U32(s.observations.saturated_count());
    w.U64(s.observations.last());
    w.Ids(s.robots);
  }
  w.U64(Fnv1a(*out));
  return Status::Ok();
}

StatusOr<std::unique_ptr<PlaneFusionEngine>> PlaneFusionEngine::LoadState(
    const PlaneFusionParams& params, std::string_view state) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  StatusOr<std::string_view> payload =
      OpenSnapshot(state, std::string_view(kPlaneMagic, sizeof(kPlaneMagic)),
                   {{kPlaneVersion, SnapshotChecksum::kFnv1a}}, {PlaneFusionParamsKey(params)},
                   "plane fusion snapshot");
  if (!payload.ok()) return payload.status();
  PlaneReader r(*payload);
  auto engine = std::make_unique<PlaneFusionEngine>(params);
  Impl& e = *engine->impl_;
  e.cluster_count_ = r.U64();
  e.plane_count_ = r.U64();
  const uint64_t n = r.Count(8 + 8 + 24 + 8 + 8 + 4 + 4 + 1);
  e.nodes_.resize(n);
  e.parent_.resize(n);
  e.size_.resize(n);
  e.stats_.resize(n);
  e.visited_.assign(n, 0);
  for (uint64_t i = 0; i < n && r.ok(); ++i) {
    PlaneNode& node = e.nodes_[i];
    node.id = r.U64();
    node.observation = r.U64();
    node.normal = r.V3();
    node.offset_m = r.F64();
    node.boundary = r.Points();
    e.parent_[i] = r.U32();
    e.size_[i] = r.U32();
    if (!r.ok() || node.boundary.size() < 3)
      return PlaneCorrupt("node " + std::to_string(i) + " is malformed");
    node.Prepare();
    if (r.U8() == 0) continue;
    auto s = std::make_unique<PlaneStats>();
    s->id = r.U64();
    s->member_count = r.U32();
    s->point_count = r.U64();
    s->mean = r.V3();
    for (int k = 0; k < 9; ++k) s->scatter(k) = r.F64();
    s->normal_sum = r.V3();
    s->hull = r.Points();
    std::vector<uint64_t> ids = r.Ids();
    const uint32_t saturated = r.U32();
    const uint64_t last = r.U64();
    s->observations = SupportCounter::FromState(std::move(ids), saturated, last);
    s->robots = r.Ids();
    e.stats_[i] = std::move(s);
  }
  if (!r.ok() || !r.at_end()) return PlaneCorrupt("truncated or trailing bytes");
  size_t roots = 0;
  for (uint64_t i = 0; i < n; ++i) {
    if (e.parent_[i] >= n)
      return PlaneCorrupt("node " + std::to_string(i) + " points outside the snapshot");
    const bool root = e.parent_[i] == i;
    if (root != (e.stats_[i] != nullptr)) return PlaneCorrupt("cluster statistics off the roots");
    roots += root;
    uint32_t x = static_cast<uint32_t>(i);
    for (int depth = 0; e.parent_[x] != x; ++depth) {
      if (depth > kMaxForestDepth) return PlaneCorrupt("a cycle in the cluster forest");
      x = e.parent_[x];
    }
  }
  if (roots != e.cluster_count_) return PlaneCorrupt("cluster count disagrees with the forest");
  for (uint32_t i = 0; i < n; ++i) e.FileInGrid(i);
  e.RebuildDerived();
  return engine;
}

}  // namespace mapd::fusion
