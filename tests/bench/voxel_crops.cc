#include "bench/voxel_crops.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>
#include <unordered_set>
#include <vector>

namespace mapd::bench {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kKeyOffset = 32768;  // VoxelGrid keys = OctoMap keys - 32768

std::uint64_t Pack(const voxel::VoxelKey& k) {
  return (static_cast<std::uint64_t>(k.x() + kKeyOffset) << 32) |
         (static_cast<std::uint64_t>(k.y() + kKeyOffset) << 16) |
         static_cast<std::uint64_t>(k.z() + kKeyOffset);
}

voxel::VoxelKey Unpack(std::uint64_t p) {
  return voxel::VoxelKey(static_cast<int>((p >> 32) & 0xffff) - kKeyOffset,
                         static_cast<int>((p >> 16) & 0xffff) - kKeyOffset,
                         static_cast<int>(p & 0xffff) - kKeyOffset);
}

bool InKeyRange(const voxel::VoxelKey& k) {
  return (k.array() >= -kKeyOffset).all() && (k.array() < kKeyOffset).all();
}

// A slab of the source map: keys with lo <= key[axis] <= hi.
struct Slab {
  int axis = 0;
  int lo = 0, hi = 0;
  bool Contains(const voxel::VoxelKey& k) const { return k[axis] >= lo && k[axis] <= hi; }
};

struct Resampled {
  std::string bt;
  std::size_t occupied = 0, free = 0;
};

// Nearest-neighbour resampling of the slab of `map` under T_out_src (see the
// header): a target voxel takes the state of the source voxel containing
// T_out_src^-1 * (its centre). Only targets near a forward-mapped occupied voxel
// are visited, which bounds both the work and the free space kept.
StatusOr<Resampled> Resample(const voxel::VoxelGrid& map, const Slab& slab,
                             const Eigen::Isometry3d& T_out_src, int band_voxels) {
  const double res = map.resolution();
  const int r = std::max(1, band_voxels);
  std::unordered_set<std::uint64_t> candidates;
  for (const voxel::VoxelKey& k : map.occupied_keys()) {
    if (!slab.Contains(k)) continue;
    const Eigen::Vector3d q = T_out_src * map.KeyToCentre(k);
    const voxel::VoxelKey t = map.PointToKey(q);
    for (int dx = -r; dx <= r; ++dx) {
      for (int dy = -r; dy <= r; ++dy) {
        for (int dz = -r; dz <= r; ++dz) {
          const voxel::VoxelKey c = t + voxel::VoxelKey(dx, dy, dz);
          if (!InKeyRange(c)) {
            return Status::FailedPrecondition("moved crop leaves OctoMap's key range");
          }
          candidates.insert(Pack(c));
        }
      }
    }
  }
  // Visit the candidates in key order so that the tree is built the same way
  // on every run (unordered_set order is an implementation detail).
  std::vector<std::uint64_t> sorted(candidates.begin(), candidates.end());
  std::sort(sorted.begin(), sorted.end());
  const Eigen::Isometry3d T_src_out = T_out_src.inverse();
  octomap::OcTree out(res);
  const float occ = out.getClampingThresMaxLog();
  const float fre = out.getClampingThresMinLog();
  Resampled result;
  for (std::uint64_t p : sorted) {
    const voxel::VoxelKey t = Unpack(p);
    const voxel::VoxelKey s = map.PointToKey(T_src_out * map.KeyToCentre(t));
    if (!slab.Contains(s)) continue;
    const voxel::VoxelState state = map.State(s);
    if (state == voxel::VoxelState::kUnknown) continue;
    const octomap::OcTreeKey key(static_cast<octomap::key_type>(t.x() + kKeyOffset),
                                 static_cast<octomap::key_type>(t.y() + kKeyOffset),
                                 static_cast<octomap::key_type>(t.z() + kKeyOffset));
    const bool occupied = state == voxel::VoxelState::kOccupied;
    out.setNodeValue(key, occupied ? occ : fre, /*lazy_eval=*/true);
    ++(occupied ? result.occupied : result.free);
  }
  out.updateInnerOccupancy();
  out.prune();
  std::ostringstream bytes;
  if (!out.writeBinary(bytes)) return Status::Internal("OcTree::writeBinary failed");
  result.bt = bytes.str();
  return result;
}

}  // namespace

Status CropParams::Validate() const {
  if (!(overlap > 0.0 && overlap < 1.0)) {
    return Status::InvalidArgument("overlap must be in (0, 1)");
  }
  if (max_occupied_per_crop < 500) {
    return Status::InvalidArgument("max_occupied_per_crop must be >= 500");
  }
  if (!(max_tilt_deg >= 0.0 && max_tilt_deg <= 90.0)) {
    return Status::InvalidArgument("max_tilt_deg must be in [0, 90]");
  }
  if (!(max_translation_m >= 0.0 && max_translation_m <= 1000.0)) {
    return Status::InvalidArgument("max_translation_m must be in [0, 1000]");
  }
  if (free_band_voxels < 0 || free_band_voxels > 8) {
    return Status::InvalidArgument("free_band_voxels must be in [0, 8]");
  }
  return Status::Ok();
}

StatusOr<CropPair> MakeCropPair(const voxel::VoxelGrid& map, const CropParams& params) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  const std::vector<voxel::VoxelKey>& keys = map.occupied_keys();
  const std::size_t total = keys.size();
  if (total < 1000) {
    return Status::FailedPrecondition("map has " + std::to_string(total) +
                                      " occupied voxels, fewer than 1000");
  }
  CropPair pair;
  const voxel::VoxelKey extent = map.max_key() - map.min_key();
  pair.axis = extent.y() > extent.x() ? 1 : 0;
  std::vector<int> u;
  u.reserve(total);
  for (const voxel::VoxelKey& k : keys) u.push_back(k[pair.axis]);
  std::sort(u.begin(), u.end());

  // Ranks along the axis: A = [s, s + n), B = [s + n - m, s + 2n - m), m = overlap * n.
  const double f = params.overlap;
  const std::size_t n = std::min(params.max_occupied_per_crop,
                                 static_cast<std::size_t>(std::floor(total / (2.0 - f))));
  const std::size_t m = static_cast<std::size_t>(std::llround(f * n));
  const std::size_t span = 2 * n - m;
  std::mt19937_64 rng(params.seed);
  std::uniform_int_distribution<std::size_t> start_dist(0, total - span);
  const std::size_t s = start_dist(rng);
  const Slab slab_a{pair.axis, u[s], u[s + n - 1]};
  const Slab slab_b{pair.axis, u[s + n - m], u[s + span - 1]};

  Eigen::Vector3d sum_b = Eigen::Vector3d::Zero();
  for (const voxel::VoxelKey& k : keys) {
    const bool in_a = slab_a.Contains(k), in_b = slab_b.Contains(k);
    pair.occupied_a += in_a;
    pair.occupied_b += in_b;
    pair.shared += in_a && in_b;
    if (in_b) sum_b += map.KeyToCentre(k);
  }
  pair.achieved_overlap =
      static_cast<double>(pair.shared) / std::min(pair.occupied_a, pair.occupied_b);
  const Eigen::Vector3d c = sum_b / static_cast<double>(pair.occupied_b);

  // The motion: yaw anywhere, roll and pitch within the tilt bound, about B's
  // centroid; then a translation drawn uniformly in a ball (rejection sampling).
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  pair.yaw_deg = 180.0 * unit(rng);
  pair.roll_deg = params.max_tilt_deg * unit(rng);
  pair.pitch_deg = params.max_tilt_deg * unit(rng);
  Eigen::Vector3d t;
  do {
    t = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
  } while (t.squaredNorm() > 1.0);
  t *= params.max_translation_m;
  pair.translation_m = t.norm();
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(pair.yaw_deg * kPi / 180.0, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(pair.pitch_deg * kPi / 180.0, Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(pair.roll_deg * kPi / 180.0, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  Eigen::Isometry3d T_b_map = Eigen::Isometry3d::Identity();
  T_b_map.linear() = R;
  T_b_map.translation() = c + t - R * c;
  pair.T_a_b = T_b_map.inverse();
  pair.centroid_b = c + t;

  StatusOr<Resampled> a =
      Resample(map, slab_a, Eigen::Isometry3d::Identity(), params.free_band_voxels);
  if (!a.ok()) return a.status();
  StatusOr<Resampled> b = Resample(map, slab_b, T_b_map, params.free_band_voxels);
  if (!b.ok()) return b.status();
  pair.a_bt = std::move(a->bt);
  pair.b_bt = std::move(b->bt);
  pair.out_occupied_a = a->occupied;
  pair.out_free_a = a->free;
  pair.out_occupied_b = b->occupied;
  pair.out_free_b = b->free;
  return pair;
}

std::uint64_t TrialSeed(std::uint64_t base_seed, const std::string& map_file_name, double overlap,
                        int trial) {
  std::uint64_t name_hash = 14695981039346656037ULL;  // FNV-1a: std::hash is not specified
  for (unsigned char c : map_file_name) name_hash = (name_hash ^ c) * 1099511628211ULL;
  return base_seed * 1000003ULL + name_hash % 1000003ULL * 10007ULL +
         static_cast<std::uint64_t>(std::llround(overlap * 100)) * 101ULL +
         static_cast<std::uint64_t>(trial);
}

double RotationErrorDeg(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth) {
  const Eigen::AngleAxisd d(est.linear().transpose() * truth.linear());
  return std::abs(d.angle()) * 180.0 / kPi;
}

double TranslationErrorAt(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth,
                          const Eigen::Vector3d& point) {
  return (est * point - truth * point).norm();
}

}  // namespace mapd::bench
