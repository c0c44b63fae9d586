// PlaneFusionEngine: parameters, input checks and the incremental
// three-criteria clustering (plane_engine.h).
#include "fusion/plane_engine.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <unordered_set>

#include "common/param_check.h"
#include "fusion/plane_engine_impl.h"

namespace mapd::fusion {
namespace {

constexpr double kMaxCoordinateM = 1e6;  // as the line engine: beyond is a unit mix-up

}  // namespace

Status PlaneFusionParams::Validate() const {
  MAPD_RETURN_IF_ERROR(CheckParamRange("plane fusion params", "max_normal_angle_rad",
                                       max_normal_angle_rad, 0.0, M_PI_2));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("plane fusion params", "max_offset_m", max_offset_m, 0.0, 1e3));
  MAPD_RETURN_IF_ERROR(
      CheckParamRange("plane fusion params", "min_overlap", min_overlap, 0.0, 1.0));
  MAPD_RETURN_IF_ERROR(CheckParamRange("plane fusion params", "max_gap_m", max_gap_m, 0.0, 1e3));
  MAPD_RETURN_IF_ERROR(CheckParamRange("plane fusion params", "cover_m", cover_m, 0.0, 1e3));
  if (min_support == 0) {
    return Status::InvalidArgument("plane fusion params: min_support must be at least 1");
  }
  return Status::Ok();
}

std::string PlaneFusionParamsKey(const PlaneFusionParams& p) {
  char text[256];
  std::snprintf(text, sizeof(text),
                "max_normal_angle_rad=%.17g max_offset_m=%.17g min_overlap=%.17g max_gap_m=%.17g "
                "min_support=%u cover_m=%.17g",
                p.max_normal_angle_rad, p.max_offset_m, p.min_overlap, p.max_gap_m, p.min_support,
                p.cover_m);
  return text;
}

// --- Impl

Status PlaneFusionEngine::Impl::Validate(const std::vector<MapPlane>& planes,
                                         std::vector<PlaneNode>* nodes) const {
  std::unordered_set<FeatureId> ids;
  nodes->reserve(planes.size());
  for (size_t i = 0; i < planes.size(); ++i) {
    const MapPlane& p = planes[i];
    const std::string name = "planes[" + std::to_string(i) + "]";
    if (!p.normal.allFinite() || !std::isfinite(p.offset_m)) {
      return Status::InvalidArgument(name + ": normal or offset is not finite");
    }
    if (std::abs(p.normal.norm() - 1.0) > 1e-3) {
      return Status::InvalidArgument(
          name + ": normal is not unit length (|n| = " + std::to_string(p.normal.norm()) + ")");
    }
    if (std::abs(p.offset_m) > kMaxCoordinateM) {
      return Status::InvalidArgument(name + ": offset_m is beyond 1e6 m");
    }
    if (p.boundary.size() < 3) {
      return Status::InvalidArgument(name + ": boundary has " + std::to_string(p.boundary.size()) +
                                     " points; at least 3 are needed");
    }
    for (size_t j = 0; j < p.boundary.size(); ++j) {
      const Eigen::Vector3d& x = p.boundary[j];
      if (!x.allFinite() || x.cwiseAbs().maxCoeff() > kMaxCoordinateM) {
        return Status::InvalidArgument(name + ".boundary[" + std::to_string(j) +
                                       "] is not finite or beyond 1e6 m");
      }
    }
    if (!ids.insert(p.id).second) {
      return Status::InvalidArgument(name + ": feature id " + std::to_string(p.id) +
                                     " is used twice in the batch");
    }
    PlaneNode n;
    n.id = p.id;
    const Eigen::Vector3d unit = p.normal.normalized();
    n.normal = CanonicalNormal(unit);
    n.offset_m = n.normal.dot(unit) > 0 ? p.offset_m : -p.offset_m;
    n.boundary = p.boundary;
    n.Prepare();
    nodes->push_back(std::move(n));
  }
  return Status::Ok();
}

bool PlaneFusionEngine::Impl::Linked(const PlaneNode& a, const PlaneNode& b) const {
  // Criterion 1.
  if (NormalAngle(a.normal, b.normal) > params_.max_normal_angle_rad) return false;
  // Criterion 2, both ways.
  if (std::abs(b.normal.dot(a.centroid) + b.offset_m) > params_.max_offset_m) return false;
  if (std::abs(a.normal.dot(b.centroid) + a.offset_m) > params_.max_offset_m) return false;
  // Criterion 3, in the common plane (symmetric in a and b).
  const Eigen::Vector3d nb = a.normal.dot(b.normal) >= 0 ? b.normal : Eigen::Vector3d(-b.normal);
  const PlaneBasis basis = PlaneBasis::Of(CanonicalNormal((a.normal + nb).normalized()));
  const std::vector<geometry::Vec2> ha = ProjectedHull(a.boundary, basis);
  const std::vector<geometry::Vec2> hb = ProjectedHull(b.boundary, basis);
  if (ConvexPolygonGap(ha, hb) > params_.max_gap_m) return false;
  if (params_.min_overlap > 0.0) {
    const double smaller = std::min(std::abs(PolygonArea(ha)), std::abs(PolygonArea(hb)));
    if (!(smaller > 0.0) || ConvexIntersectionArea(ha, hb) < params_.min_overlap * smaller)
      return false;
  }
  return true;
}

bool PlaneFusionEngine::Impl::Covered(const PlaneNode& p, const PlaneStats& s) const {
  Eigen::Vector3d normal;
  double offset_m;
  s.Fit(&normal, &offset_m);
  if (NormalAngle(p.normal, normal) > params_.max_normal_angle_rad) return false;
  const PlaneBasis basis = PlaneBasis::Of(normal);
  std::vector<geometry::Vec2> hull;
  hull.reserve(s.hull.size());
  for (const Eigen::Vector3d& x : s.hull) hull.push_back(basis.Project(x));
  for (const Eigen::Vector3d& x : p.boundary) {
    if (std::abs(normal.dot(x) + offset_m) > params_.max_offset_m) return false;
    if (!NearConvexPolygon(hull, basis.Project(x), params_.cover_m)) return false;
  }
  return true;
}

double PlaneFusionEngine::Impl::Margin(const PlaneNode& n) const {
  // Two linked planes' ground projections are within max_gap_m plus the
  // spread along the common normal, which criteria 1 and 2 bound by the
  // offset and the planes' extents times the angle: each side files or
  // queries with its share, generously (see plane_engine.h).
  return params_.max_offset_m + 2.0 * n.radius_m * std::sin(params_.max_normal_angle_rad) + 1e-6;
}

void PlaneFusionEngine::Impl::FileInGrid(uint32_t i) {
  const PlaneNode& n = nodes_[i];
  const double m = Margin(n);
  const geometry::Vec2 lo = n.ground_min.array() - m, hi = n.ground_max.array() + m;
  const CellKey a = grid_.KeyOf(lo), b = grid_.KeyOf(hi);
  if ((b.x - a.x + 1) * (b.y - a.y + 1) > kMaxCellsPerPlane) {
    large_nodes_.push_back(i);
    return;
  }
  for (int64_t x = a.x; x <= b.x; ++x) {
    for (int64_t y = a.y; y <= b.y; ++y) {
      grid_.Insert({(static_cast<double>(x) + 0.5) * kPlaneCellM,
                    (static_cast<double>(y) + 0.5) * kPlaneCellM},
                   i);
    }
  }
}

uint32_t PlaneFusionEngine::Impl::FindConst(uint32_t x) const {
  while (parent_[x] != x) x = parent_[x];
  return x;
}

uint32_t PlaneFusionEngine::Impl::Find(uint32_t x) {
  uint32_t root = FindConst(x);
  while (parent_[x] != root) {
    const uint32_t next = parent_[x];
    parent_[x] = root;
    x = next;
  }
  return root;
}

uint32_t PlaneFusionEngine::Impl::Union(uint32_t a, uint32_t b,
                                        std::vector<ClusterId>* merged_ids) {
  a = Find(a);
  b = Find(b);
  if (a == b) return a;
  if (size_[a] < size_[b] || (size_[a] == size_[b] && a > b)) std::swap(a, b);
  merged_ids->push_back(stats_[a]->id);
  merged_ids->push_back(stats_[b]->id);
  root_of_id_.erase(stats_[a]->id);
  root_of_id_.erase(stats_[b]->id);
  parent_[b] = a;
  size_[a] += size_[b];
  stats_[a]->Merge(std::move(*stats_[b]), support_cap_);
  stats_[b].reset();
  root_of_id_[stats_[a]->id] = a;
  --cluster_count_;
  return a;
}

void PlaneFusionEngine::Impl::Add(ObservationId observation, RobotId robot,
                                  std::vector<PlaneNode> batch, PlaneChangeFeed* changes) {
  std::vector<ClusterId> merged_ids;
  std::vector<uint32_t> touched;  // nodes whose cluster changed
  for (PlaneNode& p : batch) {
    p.observation = observation;
    ++plane_count_;
    // Candidates: nodes of other observations filed near p's ground projection.
    const double reach = params_.max_gap_m + Margin(p);
    const geometry::Vec2 centre = 0.5 * (p.ground_min + p.ground_max);
    const double half = 0.5 * (p.ground_max - p.ground_min).maxCoeff() + reach;
    ++stamp_;
    std::vector<uint32_t> links;
    // Clusters p is already linked to: a node of one of them needs no test,
    // since only the set of linked clusters matters (a big floor is one
    // cluster of many nodes, and the polygon test is the costly part).
    std::vector<uint32_t> linked_roots;
    const auto consider = [&](uint32_t c) {
      if (visited_[c] == stamp_) return;
      visited_[c] = stamp_;
      const PlaneNode& q = nodes_[c];
      if (q.observation == observation) return;
      const uint32_t root = Find(c);
      if (std::find(linked_roots.begin(), linked_roots.end(), root) != linked_roots.end()) return;
      if (q.ground_max.x() < p.ground_min.x() - reach - Margin(q) ||
          q.ground_min.x() > p.ground_max.x() + reach + Margin(q) ||
          q.ground_max.y() < p.ground_min.y() - reach - Margin(q) ||
          q.ground_min.y() > p.ground_max.y() + reach + Margin(q)) {
        return;
      }
      if (Linked(p, q)) {
        links.push_back(c);
        linked_roots.push_back(root);
      }
    };
    grid_.ForEachNear(centre, half, consider);
    for (uint32_t c : large_nodes_) consider(c);
    std::sort(links.begin(), links.end());  // grid order is not node order
    std::set<uint32_t> roots;
    for (uint32_t c : links) roots.insert(Find(c));
    if (roots.size() == 1) {
      PlaneStats& s = *stats_[*roots.begin()];
      if (s.observations.count() >= support_cap_ && Covered(p, s)) {
        // Folded: the cluster takes it in; p is not kept as a node.
        const uint32_t root = *roots.begin();
        const ClusterId old_id = s.id;
        s.Merge(PlaneStats::OfNode(p, robot, support_cap_), support_cap_);
        if (s.id != old_id) {
          merged_ids.push_back(old_id);
          root_of_id_.erase(old_id);
          root_of_id_[s.id] = root;
        }
        touched.push_back(root);
        continue;
      }
    }
    const uint32_t n = static_cast<uint32_t>(nodes_.size());
    nodes_.push_back(std::move(p));
    parent_.push_back(n);
    size_.push_back(1);
    visited_.push_back(stamp_);
    stats_.push_back(
        std::make_unique<PlaneStats>(PlaneStats::OfNode(nodes_[n], robot, support_cap_)));
    root_of_id_[stats_[n]->id] = n;
    ++cluster_count_;
    FileInGrid(n);
    for (uint32_t c : links) Union(n, c, &merged_ids);
    touched.push_back(n);
  }

  // Publish what changed.
  std::set<ClusterId> gone(merged_ids.begin(), merged_ids.end());
  std::set<uint32_t> roots;
  for (uint32_t n : touched) roots.insert(Find(n));
  std::vector<ClusterId> added, updated, removed;
  for (uint32_t r : roots) {
    const PlaneStats& s = *stats_[r];
    gone.erase(s.id);
    if (s.observations.count() < params_.min_support) {
      if (published_.erase(s.id) > 0) removed.push_back(s.id);
      continue;
    }
    const bool was = published_.count(s.id) > 0;
    published_[s.id] = s.ToFused();
    (was ? updated : added).push_back(s.id);
  }
  for (ClusterId id : gone) {
    if (published_.erase(id) > 0) removed.push_back(id);
  }
  if (changes) {
    std::sort(added.begin(), added.end());
    std::sort(updated.begin(), updated.end());
    changes->added = std::move(added);
    changes->updated = std::move(updated);
    changes->removed = std::move(removed);
  }
}

void PlaneFusionEngine::Impl::RebuildDerived() {
  root_of_id_.clear();
  published_.clear();
  for (uint32_t i = 0; i < nodes_.size(); ++i) {
    if (!stats_[i]) continue;
    root_of_id_[stats_[i]->id] = i;
    if (stats_[i]->observations.count() >= params_.min_support) {
      published_[stats_[i]->id] = stats_[i]->ToFused();
    }
  }
}

// --- PlaneFusionEngine

PlaneFusionEngine::PlaneFusionEngine(const PlaneFusionParams& params)
    : impl_(std::make_unique<Impl>(params)) {}
PlaneFusionEngine::~PlaneFusionEngine() = default;
PlaneFusionEngine::PlaneFusionEngine(PlaneFusionEngine&&) noexcept = default;
PlaneFusionEngine& PlaneFusionEngine::operator=(PlaneFusionEngine&&) noexcept = default;

StatusOr<std::unique_ptr<PlaneFusionEngine>> PlaneFusionEngine::Create(
    const PlaneFusionParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  return std::make_unique<PlaneFusionEngine>(params);
}

Status PlaneFusionEngine::Add(ObservationId observation, RobotId robot,
                              const std::vector<MapPlane>& planes, PlaneChangeFeed* changes) {
  if (changes) *changes = {};
  std::vector<PlaneNode> nodes;
  MAPD_RETURN_IF_ERROR(impl_->Validate(planes, &nodes));
  impl_->Add(observation, robot, std::move(nodes), changes);
  return Status::Ok();
}

std::vector<FusedPlane> PlaneFusionEngine::Published() const {
  std::vector<FusedPlane> out;
  out.reserve(impl_->published_.size());
  for (const auto& [id, f] : impl_->published_) out.push_back(f);
  return out;
}

std::optional<FusedPlane> PlaneFusionEngine::Get(ClusterId id) const {
  auto it = impl_->root_of_id_.find(id);
  if (it == impl_->root_of_id_.end()) return std::nullopt;
  return impl_->stats_[it->second]->ToFused();
}

size_t PlaneFusionEngine::plane_count() const { return impl_->plane_count_; }
size_t PlaneFusionEngine::node_count() const { return impl_->nodes_.size(); }
size_t PlaneFusionEngine::cluster_count() const { return impl_->cluster_count_; }
size_t PlaneFusionEngine::published_count() const { return impl_->published_.size(); }
const PlaneFusionParams& PlaneFusionEngine::params() const { return impl_->params_; }

}  // namespace mapd::fusion
