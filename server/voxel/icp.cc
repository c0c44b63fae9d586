#include "voxel/icp.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "voxel/aligned_box.h"
#include "voxel/nearest_voxel.h"

namespace mapd::voxel {
namespace {

using Box = Eigen::AlignedBox3d;

Box BoundsOf(const std::vector<Eigen::Vector3d>& points) {
  Box box;
  for (const auto& p : points) box.extend(p);
  return box;
}

Box Grown(Box box, double margin) {
  box.min().array() -= margin;
  box.max().array() += margin;
  return box;
}

bool AllFinite(const std::vector<Eigen::Vector3d>& points) {
  return std::all_of(points.begin(), points.end(),
                     [](const Eigen::Vector3d& p) { return p.allFinite(); });
}

// Closed-form rigid fit of dst ~ T src (Umeyama without scaling).
Eigen::Isometry3d FitPairs(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.matrix() = Eigen::umeyama(src, dst, false);
  return T;
}

// The nearest target of a query point: an index of its own, or a shared
// one asked only for its points inside `within`.
class NearestTarget {
 public:
  NearestTarget(const std::vector<Eigen::Vector3d>& target, double voxel_m)
      : owned_(std::make_unique<NearestVoxelIndex>(target, voxel_m)), index_(owned_.get()) {}
  NearestTarget(const NearestVoxelIndex* shared, const Box* within)
      : index_(shared), within_(within) {}

  // others_m2: see NearestVoxelIndex::Nearest.
  int Nearest(const Eigen::Vector3d& q, double max_m, float* squared_m2,
              double* others_m2 = nullptr) const {
    return index_->Nearest(q, max_m, squared_m2, within_, others_m2);
  }

 private:
  std::unique_ptr<NearestVoxelIndex> owned_;
  const NearestVoxelIndex* index_ = nullptr;
  const Box* within_ = nullptr;
};

// A source point's last searched pairing: the query it was searched for,
// the target found (-1: none, or not searched yet) and a lower bound on the
// squared distance from that query of every other target that counts.
struct Pairing {
  Eigen::Vector3d query;
  int target = -1;
  double others_m2 = 0.0;
};

// Whether `pairing` still holds for the query q, exactly: when q has moved by
// s from the query searched for, every other target is at least
// sqrt(others_m2) - s from q, so the paired target at distance d < that is
// still the nearest (strictly: no tie to break). Late ICP iterations move the
// source by hundredths of a voxel, and most pairs are kept without a search:
// a search is ~3,000 instructions (rings of cells), this test ~30.
// The squared distance is computed as the search computes it, bit for bit.
bool StillNearest(const Pairing& pairing, const Eigen::Vector3d& q,
                  const std::vector<Eigen::Vector3d>& target, double max_m, float* squared_m2) {
  if (pairing.target < 0) return false;
  const double d2 = (target[static_cast<std::size_t>(pairing.target)] - q).squaredNorm();
  if (!(d2 < max_m * max_m * (1 - 1e-9))) return false;
  const double moved = (q - pairing.query).norm();
  // The margins cover rounding, far below any gap that matters.
  if (!((std::sqrt(d2) + moved) * (1 + 1e-9) + 1e-12 < std::sqrt(pairing.others_m2))) return false;
  *squared_m2 = static_cast<float>(d2);
  return true;
}

struct Pairs {
  std::vector<int> source_index;
  std::vector<int> target_index;
  std::vector<float> squared_distance_m2;
};

// Nearest target of every source point under T, within max_distance_m, then
// the closest trim_fraction of them. With `pairings` (one per source point,
// kept between calls; null: search every point), a pairing that provably holds
// still is kept without a search (StillNearest): the same pairs either way.
Pairs Correspond(const NearestTarget& nearest, const std::vector<Eigen::Vector3d>& target,
                 const std::vector<Eigen::Vector3d>& source, const Eigen::Isometry3d& T,
                 double max_distance_m, double trim_fraction, std::vector<Pairing>* pairings,
                 std::size_t* searches) {
  std::vector<std::pair<float, std::pair<int, int>>> found;
  found.reserve(source.size());
  for (std::size_t i = 0; i < source.size(); ++i) {
    float sq = 0.0f;
    const Eigen::Vector3d q = T * source[i];
    int index = -1;
    if (pairings == nullptr) {
      index = nearest.Nearest(q, max_distance_m, &sq);
      ++*searches;
    } else if (Pairing& pairing = (*pairings)[i];
               StillNearest(pairing, q, target, max_distance_m, &sq)) {
      index = pairing.target;
    } else {
      index = nearest.Nearest(q, max_distance_m, &sq, &pairing.others_m2);
      pairing.query = q;
      pairing.target = index;
      ++*searches;
    }
    if (index < 0) continue;
    found.push_back({sq, {static_cast<int>(i), index}});
  }
  const std::size_t keep =
      static_cast<std::size_t>(std::ceil(trim_fraction * static_cast<double>(found.size())));
  if (keep < found.size()) {
    std::nth_element(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(keep), found.end());
    found.resize(keep);
  }
  Pairs pairs;
  for (const auto& f : found) {
    pairs.squared_distance_m2.push_back(f.first);
    pairs.source_index.push_back(f.second.first);
    pairs.target_index.push_back(f.second.second);
  }
  return pairs;
}

}  // namespace

Status IcpParams::Validate() const {
  if (max_iterations < 1) return Status::InvalidArgument("icp.max_iterations must be >= 1");
  if (!(max_correspondence_voxels > 0) || !std::isfinite(max_correspondence_voxels)) {
    return Status::InvalidArgument("icp.max_correspondence_voxels must be finite and > 0");
  }
  if (!(trim_fraction > 0 && trim_fraction <= 1)) {
    return Status::InvalidArgument("icp.trim_fraction must be in (0, 1]");
  }
  if (!(convergence_rotation_rad >= 0) || !std::isfinite(convergence_rotation_rad)) {
    return Status::InvalidArgument("icp.convergence_rotation_rad must be finite and >= 0");
  }
  if (!(convergence_translation_voxels >= 0) || !std::isfinite(convergence_translation_voxels)) {
    return Status::InvalidArgument("icp.convergence_translation_voxels must be finite and >= 0");
  }
  if (!(convergence_rms_relative >= 0) || !std::isfinite(convergence_rms_relative)) {
    return Status::InvalidArgument("icp.convergence_rms_relative must be finite and >= 0");
  }
  if (min_inliers < 3) return Status::InvalidArgument("icp.min_inliers must be >= 3");
  return Status::Ok();
}

namespace {

// RefineIcp (EvaluateIcp when !iterate) with the target's index either built here, over the target
// points of the overlap (shared == null), or shared, over all of them and
// asked within the overlap's box; target_index then counts in `target`.
StatusOr<IcpResult> Refine(const std::vector<Eigen::Vector3d>& target,
                           const NearestVoxelIndex* shared,
                           const std::vector<Eigen::Vector3d>& source,
                           const Eigen::Isometry3d& T_init, double voxel_size_m,
                           const IcpParams& params, bool iterate) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  if (!(voxel_size_m > 0) || !std::isfinite(voxel_size_m)) {
    return Status::InvalidArgument("voxel size must be finite and > 0");
  }
  if (!T_init.matrix().allFinite() || !AllFinite(target) || !AllFinite(source)) {
    return Status::InvalidArgument("ICP input is not finite");
  }
  const double max_distance_m = params.max_correspondence_voxels * voxel_size_m;
  IcpResult result;
  result.T_target_source = T_init;
  if (target.empty() || source.empty()) {
    return Status::FailedPrecondition("ICP: empty point set");
  }

  // The overlap, judged from the initial transform.
  // Source points within the target's box grown by half a voxel only: beyond
  // the cut end of a wall, source points would pair with the target's last
  // column of voxels and pull the fit along the wall.
  const Box target_box = Grown(BoundsOf(target), 0.5 * voxel_size_m);
  const Box source_box = Grown(TransformedBox(BoundsOf(source), T_init), max_distance_m);
  std::vector<Eigen::Vector3d> src;
  for (const auto& p : source) {
    if (target_box.contains(T_init * p)) src.push_back(p);
  }
  if (params.max_source_points > 0 && src.size() > params.max_source_points) {
    // Even stride over the (lexicographically ordered) points: deterministic.
    std::vector<Eigen::Vector3d> sub;
    sub.reserve(params.max_source_points);
    const double stride =
        static_cast<double>(src.size()) / static_cast<double>(params.max_source_points);
    for (std::size_t i = 0; i < params.max_source_points; ++i) {
      sub.push_back(src[static_cast<std::size_t>(static_cast<double>(i) * stride)]);
    }
    src.swap(sub);
  }
  std::vector<Eigen::Vector3d> subset;
  std::size_t in_overlap = 0;
  for (const auto& p : target) {
    if (!source_box.contains(p)) continue;
    ++in_overlap;
    if (shared == nullptr) subset.push_back(p);
  }
  result.source_points = src.size();
  result.target_points = in_overlap;
  if (static_cast<int>(src.size()) < params.min_inliers ||
      static_cast<int>(in_overlap) < params.min_inliers) {
    return Status::FailedPrecondition(
        "ICP: the maps do not overlap (" + std::to_string(src.size()) + " source and " +
        std::to_string(in_overlap) + " target points in the overlap)");
  }
  const std::vector<Eigen::Vector3d>& tgt = shared == nullptr ? subset : target;
  const NearestTarget tree =
      shared == nullptr ? NearestTarget(tgt, voxel_size_m) : NearestTarget(shared, &source_box);
  double previous_rms = -1.0;
  std::vector<Pairing> pairings;
  if (params.reuse_pairings) {
    pairings.resize(src.size());
  }
  std::vector<Pairing>* reuse = pairings.empty() ? nullptr : &pairings;

  Eigen::Isometry3d T = T_init;
  if (!iterate) result.converged = true;
  for (int iteration = 0; iterate && iteration < params.max_iterations; ++iteration) {
    const Pairs pairs = Correspond(tree, tgt, src, T, max_distance_m, params.trim_fraction, reuse,
                                   &result.searches);
    const int n = static_cast<int>(pairs.source_index.size());
    if (n < params.min_inliers) {
      return Status::FailedPrecondition("ICP: only " + std::to_string(n) +
                                        " correspondences within " +
                                        std::to_string(params.max_correspondence_voxels) +
                                        " voxels, need " + std::to_string(params.min_inliers));
    }
    Eigen::Matrix3Xd s(3, n), d(3, n);
    for (int i = 0; i < n; ++i) {
      s.col(i) = src[static_cast<std::size_t>(pairs.source_index[static_cast<std::size_t>(i)])];
      d.col(i) = tgt[static_cast<std::size_t>(pairs.target_index[static_cast<std::size_t>(i)])];
    }
    double sum = 0.0;
    for (float sq : pairs.squared_distance_m2) sum += sq;
    const double rms = std::sqrt(sum / n);
    const bool rms_settled =
        previous_rms >= 0 &&
        std::abs(previous_rms - rms) <= params.convergence_rms_relative * previous_rms;
    previous_rms = rms;
    const Eigen::Isometry3d T_new = FitPairs(s, d);
    const Eigen::Isometry3d step = T_new * T.inverse();
    T = T_new;
    result.iterations = iteration + 1;
    const double rotation = Eigen::AngleAxisd(step.linear()).angle();
    const double translation = step.translation().norm() / voxel_size_m;
    if ((rotation < params.convergence_rotation_rad &&
         translation < params.convergence_translation_voxels) ||
        rms_settled) {
      result.converged = true;
      break;
    }
  }
  // Final evaluation with the final transform.
  const Pairs pairs =
      Correspond(tree, tgt, src, T, max_distance_m, params.trim_fraction, reuse, &result.searches);
  if (static_cast<int>(pairs.source_index.size()) < params.min_inliers) {
    return Status::FailedPrecondition("ICP: too few correspondences after refinement");
  }
  double sum = 0.0;
  for (float sq : pairs.squared_distance_m2) sum += sq;
  result.T_target_source = T;
  result.inliers = static_cast<int>(pairs.source_index.size());
  result.rms_residual_m = std::sqrt(sum / static_cast<double>(result.inliers));
  return result;
}

}  // namespace

IcpTarget::IcpTarget(const std::vector<Eigen::Vector3d>* points, double voxel_size_m)
    : points_(points), voxel_size_m_(voxel_size_m) {
  if (!(voxel_size_m > 0) || !std::isfinite(voxel_size_m)) {
    status_ = Status::InvalidArgument("voxel size must be finite and > 0");
  } else if (!AllFinite(*points)) {
    status_ = Status::InvalidArgument("ICP input is not finite");
  } else {
    index_ = std::make_unique<NearestVoxelIndex>(*points, voxel_size_m);
  }
}

IcpTarget::~IcpTarget() = default;

StatusOr<IcpResult> RefineIcp(const std::vector<Eigen::Vector3d>& target,
                              const std::vector<Eigen::Vector3d>& source,
                              const Eigen::Isometry3d& T_init, double voxel_size_m,
                              const IcpParams& params) {
  return Refine(target, nullptr, source, T_init, voxel_size_m, params, /*iterate=*/true);
}

StatusOr<IcpResult> RefineIcp(const IcpTarget& target, const std::vector<Eigen::Vector3d>& source,
                              const Eigen::Isometry3d& T_init, const IcpParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  MAPD_RETURN_IF_ERROR(target.status());
  return Refine(target.points(), &target.index(), source, T_init, target.voxel_size_m(), params,
                /*iterate=*/true);
}

StatusOr<IcpResult> EvaluateIcp(const IcpTarget& target, const std::vector<Eigen::Vector3d>& source,
                                const Eigen::Isometry3d& T, const IcpParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  MAPD_RETURN_IF_ERROR(target.status());
  return Refine(target.points(), &target.index(), source, T, target.voxel_size_m(), params,
                /*iterate=*/false);
}

}  // namespace mapd::voxel
