#include "voxel/corner_extraction.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/clock.h"
#include "voxel/corner_faces.h"
#include "voxel/corner_voxel_index.h"
#include "voxel/corner_window.h"
#include "voxel/normals_grid.h"
#include "voxel/plane_regions.h"

namespace mapd::voxel {
namespace {

using Clock = std::chrono::steady_clock;
using internal::FittedPlane;
using PlaneTriple = std::array<int, 3>;  // ascending plane indices

// Voxel units: the centre of voxel `key` is key + 0.5, so metres = units * res.
Eigen::Vector3d Centre(const VoxelKey& key) {
  return key.cast<double>() + Eigen::Vector3d::Constant(0.5);
}

// Distance from the plane to the unit voxel cube centred at `p` (0 when the
// plane cuts the voxel).
double VoxelDistance(const FittedPlane& plane, const Eigen::Vector3d& p) {
  return std::max(0.0, plane.Distance(p) - 0.5 * plane.normal.cwiseAbs().sum());
}

std::uint64_t PackCell(const VoxelKey& cell) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(cell.x()) & 0x1fffff) << 42) |
         (static_cast<std::uint64_t>(static_cast<std::uint32_t>(cell.y()) & 0x1fffff) << 21) |
         (static_cast<std::uint64_t>(static_cast<std::uint32_t>(cell.z()) & 0x1fffff));
}

VoxelKey CellOf(const VoxelKey& key, int edge) {
  auto floor_div = [edge](int a) { return a >= 0 ? a / edge : -((-a + edge - 1) / edge); };
  return {floor_div(key.x()), floor_div(key.y()), floor_div(key.z())};
}

// The planes with a voxel in each cell of edge `edge` voxels.
std::unordered_map<std::uint64_t, std::vector<int>> PlanesByCell(const std::vector<VoxelKey>& keys,
                                                                 const std::vector<int>& label,
                                                                 int edge) {
  std::unordered_map<std::uint64_t, std::vector<int>> cells;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (label[i] < 0) continue;
    std::vector<int>& planes = cells[PackCell(CellOf(keys[i], edge))];
    if (std::find(planes.begin(), planes.end(), label[i]) == planes.end()) {
      planes.push_back(label[i]);
    }
  }
  return cells;
}

// B.2 for one candidate: every triple among its nearest planes (within
// epsilon of the voxel, a voxel in a neighbouring cell) that are pairwise
// min_plane_angle apart.
void CandidateTriples(const Eigen::Vector3d& p, const VoxelKey& cell,
                      const std::unordered_map<std::uint64_t, std::vector<int>>& cells,
                      const std::vector<FittedPlane>& planes, const CornerExtractionParams& params,
                      double min_cos_separation, std::vector<PlaneTriple>* triples) {
  std::vector<std::pair<double, int>> near;
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dz = -1; dz <= 1; ++dz) {
        const auto it = cells.find(PackCell(cell + VoxelKey(dx, dy, dz)));
        if (it == cells.end()) continue;
        for (int plane : it->second) {
          const double d = VoxelDistance(planes[static_cast<std::size_t>(plane)], p);
          if (d > params.plane_epsilon) continue;
          if (std::none_of(near.begin(), near.end(),
                           [plane](const auto& e) { return e.second == plane; })) {
            near.emplace_back(d, plane);
          }
        }
      }
    }
  }
  if (near.size() < 3) return;
  std::sort(near.begin(), near.end());
  if (static_cast<int>(near.size()) > params.max_planes_per_candidate) {
    near.resize(static_cast<std::size_t>(params.max_planes_per_candidate));
  }
  auto apart = [&](int a, int b) {
    return std::abs(planes[static_cast<std::size_t>(a)].normal.dot(
               planes[static_cast<std::size_t>(b)].normal)) <= min_cos_separation;
  };
  const std::size_t n = near.size();
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      if (!apart(near[i].second, near[j].second)) continue;
      for (std::size_t k = j + 1; k < n; ++k) {
        if (!apart(near[i].second, near[k].second) || !apart(near[j].second, near[k].second)) {
          continue;
        }
        PlaneTriple t{near[i].second, near[j].second, near[k].second};
        std::sort(t.begin(), t.end());
        triples->push_back(t);
      }
    }
  }
}

// Orients `normal` (of a face through `face_point`) towards free space as seen
// in the grid; when the grid knows no free space there, away from the corner's
// other faces (`other_faces`: a point on them near the corner). Metres.
Eigen::Vector3d OrientNormal(const VoxelGrid& grid, const Eigen::Vector3d& normal,
                             const Eigen::Vector3d& face_point,
                             const Eigen::Vector3d& other_faces) {
  int vote = 0;  // > 0: free space on the +normal side
  for (int step = 1; step <= 3; ++step) {
    const Eigen::Vector3d offset = normal * (step * grid.resolution());
    vote += grid.State(grid.PointToKey(face_point + offset)) == VoxelState::kFree;
    vote -= grid.State(grid.PointToKey(face_point - offset)) == VoxelState::kFree;
  }
  if (vote == 0) vote = normal.dot(other_faces - face_point) < 0.0 ? 1 : -1;
  return vote > 0 ? normal : Eigen::Vector3d(-normal);
}

// A corner hypothesis: one plane triple that meets.
struct Hypothesis {
  internal::MeetingFaces faces;
  std::vector<int> members;  // candidates (indices into the candidate list)
};

}  // namespace

Status CornerExtractionParams::Validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (window_size < 3 || window_size > 31 || window_size % 2 == 0) {
    return Status::InvalidArgument("window_size must be odd and in [3, 31]");
  }
  if (tau_change < 1) return Status::InvalidArgument("tau_change must be >= 1");
  if (!positive(plane_epsilon)) return Status::InvalidArgument("plane_epsilon must be > 0");
  if (!(min_plane_angle_deg >= 0.0 && min_plane_angle_deg < 90.0)) {
    return Status::InvalidArgument("min_plane_angle_deg must be in [0, 90)");
  }
  if (!(plane_search_radius >= 1.0 && plane_search_radius <= 64.0)) {
    return Status::InvalidArgument("plane_search_radius must be in [1, 64]");
  }
  if (!(normal_radius >= 1.0 && normal_radius <= 16.0)) {
    return Status::InvalidArgument("normal_radius must be in [1, 16]");
  }
  if (!(smoothness_deg > 0.0 && smoothness_deg < 90.0)) {
    return Status::InvalidArgument("smoothness_deg must be in (0, 90)");
  }
  if (!(region_angle_deg > 0.0 && region_angle_deg < 90.0)) {
    return Status::InvalidArgument("region_angle_deg must be in (0, 90)");
  }
  if (!positive(curvature_threshold)) {
    return Status::InvalidArgument("curvature_threshold must be > 0");
  }
  if (!positive(max_region_plane_distance)) {
    return Status::InvalidArgument("max_region_plane_distance must be > 0");
  }
  if (min_region_size < 3) return Status::InvalidArgument("min_region_size must be >= 3");
  if (!positive(max_plane_rms)) return Status::InvalidArgument("max_plane_rms must be > 0");
  if (!(face_support_radius >= 1.0 && face_support_radius <= 64.0)) {
    return Status::InvalidArgument("face_support_radius must be in [1, 64]");
  }
  if (!positive(face_band)) return Status::InvalidArgument("face_band must be > 0");
  if (min_face_support < 3) return Status::InvalidArgument("min_face_support must be >= 3");
  if (!(min_normal_determinant > 0.0 && min_normal_determinant <= 1.0)) {
    return Status::InvalidArgument("min_normal_determinant must be in (0, 1]");
  }
  if (refine_iterations < 0 || refine_iterations > 10) {
    return Status::InvalidArgument("refine_iterations must be in [0, 10]");
  }
  if (max_planes_per_candidate < 3 || max_planes_per_candidate > 16) {
    return Status::InvalidArgument("max_planes_per_candidate must be in [3, 16]");
  }
  if (!positive(cluster_radius)) return Status::InvalidArgument("cluster_radius must be > 0");
  if (!positive(max_corner_offset)) {
    return Status::InvalidArgument("max_corner_offset must be > 0");
  }
  if (max_table_bytes == 0) return Status::InvalidArgument("max_table_bytes must be > 0");
  if (scale < 1 || scale > 64) return Status::InvalidArgument("scale must be in [1, 64]");
  return Status::Ok();
}

namespace {

// The map coarsened by `scale`: coarse key floor(key / scale), so coarse voxel
// c covers exactly the fine voxels [c * scale, (c + 1) * scale).
StatusOr<VoxelGrid> Coarsen(const VoxelGrid& grid, int scale) {
  auto floor_div = [scale](int a) { return a >= 0 ? a / scale : -((-a + scale - 1) / scale); };
  std::vector<VoxelKey> keys;
  keys.reserve(grid.num_occupied());
  for (const VoxelKey& k : grid.occupied_keys()) {
    keys.emplace_back(floor_div(k.x()), floor_div(k.y()), floor_div(k.z()));
  }
  return VoxelGrid::FromKeys(grid.resolution() * scale, keys);
}

}  // namespace

StatusOr<CornerExtractionResult> ExtractCorners(const VoxelGrid& original,
                                                const CornerExtractionParams& params,
                                                const internal::GridSurface* surface) {
  MAPD_RETURN_IF_ERROR(params.Validate());
  CornerExtractionResult result;
  result.occupied_voxels = original.num_occupied();
  if (original.num_occupied() > params.max_occupied_voxels) {
    return Status::ResourceExhausted("map has " + std::to_string(original.num_occupied()) +
                                     " occupied voxels; the limit is " +
                                     std::to_string(params.max_occupied_voxels));
  }
  result.scale = params.scale;
  VoxelGrid coarse;
  if (result.scale > 1 && !original.empty()) {
    StatusOr<VoxelGrid> coarsened = Coarsen(original, result.scale);
    if (!coarsened.ok()) return coarsened.status();
    coarse = std::move(coarsened).value();
  }
  const VoxelGrid& grid = result.scale > 1 ? coarse : original;
  result.working_voxels = grid.num_occupied();
  const double res = grid.resolution();
  const std::vector<VoxelKey>& keys = grid.occupied_keys();

  // B.1: candidates by the sliding window.
  auto start = Clock::now();
  StatusOr<internal::WindowCandidates> window = internal::FindWindowCandidates(
      grid, params.window_size, params.tau_change, params.max_table_bytes);
  if (!window.ok()) return window.status();
  result.candidates = window->keys.size();
  result.table_blocks = window->blocks;
  result.seconds_window = SecondsSince(start);
  if (window->keys.empty()) return result;

  // B.2: normals and planar regions on the grid.
  start = Clock::now();
  std::optional<internal::GridSurface> own;
  if (surface == nullptr || result.scale > 1 || surface->radius_voxels != params.normal_radius) {
    surface = &own.emplace(keys, params.normal_radius);
  }
  const internal::VoxelIndex& index = surface->index;
  const internal::GridNormals& normals = surface->normals;
  result.seconds_normals = SecondsSince(start);
  start = Clock::now();
  internal::PlaneRegionParams region_params;
  region_params.smoothness_deg = params.smoothness_deg;
  region_params.region_angle_deg = params.region_angle_deg;
  region_params.curvature_threshold = params.curvature_threshold;
  region_params.max_plane_distance = params.max_region_plane_distance;
  region_params.min_region_size = params.min_region_size;
  region_params.max_plane_rms = params.max_plane_rms;
  const internal::PlaneRegions regions =
      internal::GrowPlaneRegions(keys, index, normals, region_params);
  result.planes = regions.planes.size();
  result.seconds_planes = SecondsSince(start);

  // B.2: each candidate's plane triples (paper eq. 3 for three planes).
  start = Clock::now();
  const int cell_edge = static_cast<int>(std::ceil(params.plane_search_radius));
  const auto cells = PlanesByCell(keys, regions.label, cell_edge);
  const double min_cos = std::cos(params.min_plane_angle_deg * M_PI / 180.0);
  std::map<PlaneTriple, std::vector<int>> members_of_triple;
  std::vector<PlaneTriple> triples;
  for (std::size_t c = 0; c < window->keys.size(); ++c) {
    const VoxelKey& key = window->keys[c];
    triples.clear();
    CandidateTriples(Centre(key), CellOf(key, cell_edge), cells, regions.planes, params, min_cos,
                     &triples);
    for (const PlaneTriple& t : triples) members_of_triple[t].push_back(static_cast<int>(c));
  }
  result.triples = members_of_triple.size();
  result.seconds_verify = SecondsSince(start);

  // B.3: a corner per triple whose planes meet near its candidates; corners
  // closer than cluster_radius are one cluster (the best supported stays).
  start = Clock::now();
  internal::FaceParams face_params;
  face_params.support_radius = params.face_support_radius;
  face_params.band = params.face_band;
  face_params.min_support = params.min_face_support;
  face_params.min_determinant = params.min_normal_determinant;
  face_params.refine_iterations = params.refine_iterations;
  std::vector<Hypothesis> hypotheses;
  std::vector<char> verified(window->keys.size(), 0);
  for (const auto& [triple, members] : members_of_triple) {
    std::array<FittedPlane, 3> planes;
    for (std::size_t k = 0; k < 3; ++k) {
      planes[k] = regions.planes[static_cast<std::size_t>(triple[k])];
    }
    // C++17 lambdas cannot capture a structured binding: name it first.
    const std::vector<int>& triple_members = members;
    auto nearest_member = [&](const Eigen::Vector3d& x) {
      double nearest = std::numeric_limits<double>::infinity();
      for (int m : triple_members) {
        nearest = std::min(nearest, (Centre(window->keys[static_cast<std::size_t>(m)]) - x).norm());
      }
      return nearest;
    };
    // The global planes' intersection first: cheap, and rejects most triples
    // before the face voxels are gathered.
    Eigen::Vector3d crossing;
    if (!internal::IntersectPlanes(planes, params.min_normal_determinant, &crossing) ||
        nearest_member(crossing) > params.max_corner_offset + params.face_support_radius) {
      continue;
    }
    Hypothesis h;
    if (!internal::FacesMeet(keys, index, planes, face_params, &h.faces)) continue;
    if (nearest_member(h.faces.position) > params.max_corner_offset) continue;
    for (int m : members) verified[static_cast<std::size_t>(m)] = 1;
    h.members = members;
    hypotheses.push_back(std::move(h));
  }
  result.verified_candidates =
      static_cast<std::size_t>(std::count(verified.begin(), verified.end(), 1));
  result.clusters = hypotheses.size();
  // Best supported first (ties: lowest triple, already the order): stable.
  std::vector<std::size_t> order(hypotheses.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto weight = [&](std::size_t i) {
    const Hypothesis& h = hypotheses[i];
    return std::min({h.faces.support[0], h.faces.support[1], h.faces.support[2]});
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return weight(a) > weight(b); });
  std::vector<Eigen::Vector3d> taken;  // voxel units
  for (std::size_t i : order) {
    const Hypothesis& h = hypotheses[i];
    bool merged = false;
    for (std::size_t t = 0; t < taken.size(); ++t) {
      if ((taken[t] - h.faces.position).norm() <= params.cluster_radius) {
        result.corners[t].support += static_cast<int>(h.members.size());
        merged = true;
        break;
      }
    }
    if (merged) continue;
    Corner corner;
    corner.position = h.faces.position * res;
    for (std::size_t k = 0; k < 3; ++k) {
      const Eigen::Vector3d others =
          0.5 * (h.faces.face_mean[(k + 1) % 3] + h.faces.face_mean[(k + 2) % 3]) * res;
      corner.normals[k] =
          OrientNormal(original, h.faces.planes[k].normal, h.faces.face_mean[k] * res, others);
    }
    corner.support = static_cast<int>(h.members.size());
    taken.push_back(h.faces.position);
    result.corners.push_back(corner);
  }
  result.seconds_cluster = SecondsSince(start);
  return result;
}

}  // namespace mapd::voxel
