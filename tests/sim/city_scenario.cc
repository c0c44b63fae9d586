#include "sim/city_scenario.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "client/robot/split_and_merge.h"

namespace mapd::fusion::scenario {

using geometry::Segment2;
using geometry::Vec2;

namespace {

constexpr double kStructureCellM = 20.0;  // ray-casting grid
constexpr double kFenceInsetM = 1.5;
constexpr double kPoleInsetM = 0.5;
constexpr double kPoleSideM = 0.3;

// SplitMix64 with Box-Muller normals: the same numbers on every platform
// (std::normal_distribution is implementation-defined).
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  double Normal(double sigma) {
    if (sigma == 0.0) return 0.0;
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  uint64_t state_;
};

Vec2 Rotate(const Vec2& p, double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  return {c * p.x() - s * p.y(), s * p.x() + c * p.y()};
}

void AddRectangle(const Vec2& centre, double half_w, double half_h, double yaw, const Vec2& pivot,
                  World* world) {
  std::vector<Vec2> c = {
      {-half_w, -half_h}, {half_w, -half_h}, {half_w, half_h}, {-half_w, half_h}};
  for (Vec2& p : c) p = pivot + Rotate(centre + p - pivot, yaw);
  world->buildings.push_back(c);
}

// The route: every horizontal road west-east/east-west in turn, then every
// vertical road, on the road centre lines, one pose per scan_spacing_m.
std::vector<Pose2> Route(const ScenarioParams& p) {
  const double pitch = p.block_m + p.road_m;
  const double x_end = p.blocks_x * pitch + 0.5 * p.road_m;
  const double y_end = p.blocks_y * pitch + 0.5 * p.road_m;
  std::vector<Vec2> way;
  for (int j = 0; j <= p.blocks_y; ++j) {
    const double y = 0.5 * p.road_m + j * pitch;
    const bool east = j % 2 == 0;
    way.push_back({east ? 0.5 * p.road_m : x_end, y});
    way.push_back({east ? x_end : 0.5 * p.road_m, y});
  }
  for (int i = 0; i <= p.blocks_x; ++i) {
    const double x = 0.5 * p.road_m + i * pitch;
    const bool north = i % 2 == 0;
    way.push_back({x, north ? 0.5 * p.road_m : y_end});
    way.push_back({x, north ? y_end : 0.5 * p.road_m});
  }
  std::vector<Pose2> route;
  double carry = 0.0;  // distance already travelled past the last pose
  for (size_t k = 0; k + 1 < way.size(); ++k) {
    const Vec2 d = way[k + 1] - way[k];
    const double length = d.norm();
    if (length == 0.0) continue;
    const double yaw = std::atan2(d.y(), d.x());
    double s = carry == 0.0 ? 0.0 : p.scan_spacing_m - carry;
    for (; s < length; s += p.scan_spacing_m) route.push_back({way[k] + (s / length) * d, yaw});
    carry = length - (s - p.scan_spacing_m);
  }
  return route;
}

}  // namespace

World GenerateWorld(const ScenarioParams& p) {
  World world;
  Rng rng(p.seed * 0x2545F4914F6CDD1DULL + 17);
  const double pitch = p.block_m + p.road_m;
  std::vector<Structure> trivial;
  for (int i = 0; i < p.blocks_x; ++i) {
    for (int j = 0; j < p.blocks_y; ++j) {
      const Vec2 lo(p.road_m + i * pitch, p.road_m + j * pitch);
      const Vec2 pivot = lo + Vec2(0.5 * p.block_m, 0.5 * p.block_m);
      const double yaw = rng.Uniform() < p.aligned_prob ? 0.0 : rng.Uniform(-1, 1) * p.max_yaw_rad;
      const double inner = p.block_m - 2.0 * p.setback_m;  // usable side
      const Vec2 in_lo = lo + Vec2(p.setback_m, p.setback_m);
      // Buildings keep to the south or the north road: depth from that edge.
      const bool south = rng.Uniform() < 0.5;
      if (rng.Uniform() < p.close_pair_prob) {
        const double gap = rng.Uniform(p.close_gap_min_m, p.close_gap_max_m);
        const double w1 = rng.Uniform(0.35, 0.65) * (inner - gap);
        const double w2 = inner - gap - w1;
        const double h1 = rng.Uniform(0.45, 0.9) * inner, h2 = rng.Uniform(0.45, 0.9) * inner;
        const double y1 = south ? in_lo.y() + 0.5 * h1 : in_lo.y() + inner - 0.5 * h1;
        const double y2 = south ? in_lo.y() + 0.5 * h2 : in_lo.y() + inner - 0.5 * h2;
        AddRectangle({in_lo.x() + 0.5 * w1, y1}, 0.5 * w1, 0.5 * h1, yaw, pivot, &world);
        AddRectangle({in_lo.x() + w1 + gap + 0.5 * w2, y2}, 0.5 * w2, 0.5 * h2, yaw, pivot, &world);
        const int b = static_cast<int>(world.buildings.size());
        world.close_pairs.push_back({b - 2, b - 1});
      } else {
        const double w = rng.Uniform(0.5, 0.95) * inner, h = rng.Uniform(0.5, 0.95) * inner;
        const double x = in_lo.x() + rng.Uniform(0.0, inner - w) + 0.5 * w;
        const double y = south ? in_lo.y() + 0.5 * h : in_lo.y() + inner - 0.5 * h;
        AddRectangle({x, y}, 0.5 * w, 0.5 * h, yaw, pivot, &world);
      }
      // Fences and poles along a random block edge, between road and building.
      for (int k = 0; k < p.fences_per_block + p.poles_per_block; ++k) {
        const int edge = static_cast<int>(rng.Next() % 4);
        const double along = rng.Uniform(3.0, p.block_m - 6.0);
        const bool fence = k < p.fences_per_block;
        const double inset = fence ? kFenceInsetM : kPoleInsetM;
        const double length = fence ? rng.Uniform(1.5, 3.0) : kPoleSideM;
        // Edge frame: origin at a block corner, u along the edge, v into the block.
        const Vec2 corners[4] = {lo, lo + Vec2(p.block_m, 0), lo + Vec2(p.block_m, p.block_m),
                                 lo + Vec2(0, p.block_m)};
        const Vec2 u = (corners[(edge + 1) % 4] - corners[edge]) / p.block_m;
        const Vec2 v(-u.y(), u.x());
        const Vec2 a = corners[edge] + along * u + inset * v;
        if (fence) {
          trivial.push_back({{a, a + length * u}, StructureKind::kTrivial, -1});
        } else {
          const Vec2 q[4] = {a, a + length * u, a + length * (u + v), a + length * v};
          for (int e = 0; e < 4; ++e) {
            trivial.push_back({{q[e], q[(e + 1) % 4]}, StructureKind::kTrivial, -1});
          }
        }
      }
    }
  }
  for (size_t b = 0; b < world.buildings.size(); ++b) {
    const std::vector<Vec2>& c = world.buildings[b];
    const int first = static_cast<int>(world.structures.size());
    for (int k = 0; k < 4; ++k) {
      world.structures.push_back({{c[static_cast<size_t>(k)], c[static_cast<size_t>((k + 1) % 4)]},
                                  StructureKind::kWall,
                                  static_cast<int>(b)});
    }
    for (int k = 0; k < 4; ++k) {
      world.corners.push_back({c[static_cast<size_t>(k)], first + (k + 3) % 4, first + k});
    }
  }
  world.wall_count = world.structures.size();
  world.structures.insert(world.structures.end(), trivial.begin(), trivial.end());
  world.route = Route(p);
  world.min = Vec2::Zero();
  world.max = Vec2(p.blocks_x * pitch + p.road_m, p.blocks_y * pitch + p.road_m);
  return world;
}

ScanSimulator::ScanSimulator(const ScenarioParams& params, const World& world)
    : params_(params), world_(world), cell_m_(kStructureCellM) {
  fan_.start_rad = -M_PI;  // beam b at the centre of sector b of 2 pi / beams
  fan_.step_rad = 2.0 * M_PI / params.beams;
  fan_.beam_offset = 0.5;
  fan_.beams = params.beams;
  fan_.max_range_m = params.max_range_m;
  cells_x_ = static_cast<int>(std::ceil(world.max.x() / cell_m_)) + 1;
  cells_y_ = static_cast<int>(std::ceil(world.max.y() / cell_m_)) + 1;
  cells_.resize(static_cast<size_t>(cells_x_ * cells_y_));
  for (size_t s = 0; s < world.structures.size(); ++s) {
    const Segment2& seg = world.structures[s].segment;
    const Vec2 lo = seg.a.cwiseMin(seg.b), hi = seg.a.cwiseMax(seg.b);
    for (int x = std::max(0, static_cast<int>(lo.x() / cell_m_));
         x <= std::min(cells_x_ - 1, static_cast<int>(hi.x() / cell_m_)); ++x) {
      for (int y = std::max(0, static_cast<int>(lo.y() / cell_m_));
           y <= std::min(cells_y_ - 1, static_cast<int>(hi.y() / cell_m_)); ++y) {
        cells_[static_cast<size_t>(x * cells_y_ + y)].push_back(static_cast<int>(s));
      }
    }
  }
}

void ScanSimulator::Ranges(size_t index, std::vector<double>* ranges,
                           std::vector<int>* hits) const {
  const Pose2& pose = world_.route[index];
  hits->assign(static_cast<size_t>(params_.beams), -1);
  // Candidate structures: those filed in the cells that the range square meets.
  std::vector<int> candidates;
  const double r = params_.max_range_m;
  const int x0 = std::max(0, static_cast<int>((pose.t.x() - r) / cell_m_));
  const int x1 = std::min(cells_x_ - 1, static_cast<int>((pose.t.x() + r) / cell_m_));
  const int y0 = std::max(0, static_cast<int>((pose.t.y() - r) / cell_m_));
  const int y1 = std::min(cells_y_ - 1, static_cast<int>((pose.t.y() + r) / cell_m_));
  for (int x = x0; x <= x1; ++x) {
    for (int y = y0; y <= y1; ++y) {
      const std::vector<int>& c = cells_[static_cast<size_t>(x * cells_y_ + y)];
      candidates.insert(candidates.end(), c.begin(), c.end());
    }
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  std::vector<Segment2> walls;
  walls.reserve(candidates.size());
  for (int c : candidates) walls.push_back(world_.structures[static_cast<size_t>(c)].segment);
  sim::LaserScan scan = sim::CastLaser(walls, pose, fan_);
  *ranges = std::move(scan.range_m);
  for (size_t k = 0; k < scan.hit.size(); ++k) {
    (*hits)[k] = scan.hit[k] < 0 ? -1 : candidates[static_cast<size_t>(scan.hit[k])];
  }
  Rng rng(params_.seed * 0x9E3779B97F4A7C15ULL + 0x1000003ULL * (index + 1));
  for (double& range : *ranges) {
    if (std::isfinite(range)) range += rng.Normal(params_.range_sigma_m);
  }
}

Scan ScanSimulator::Simulate(size_t index) const {
  std::vector<double> ranges;
  std::vector<int> hits;
  Ranges(index, &ranges, &hits);
  Scan scan;
  scan.observation = index + 1;
  scan.true_pose = world_.route[index];
  Rng rng(params_.seed * 0xD1B54A32D192ED03ULL + 0x2000003ULL * (index + 1));
  scan.estimated_pose = scan.true_pose;
  scan.estimated_pose.t +=
      Vec2(rng.Normal(params_.pose_sigma_xy_m), rng.Normal(params_.pose_sigma_xy_m));
  scan.estimated_pose.yaw_rad += rng.Normal(params_.pose_sigma_yaw_rad);

  // Beam order; a beam without a return is NaN, which ends a run.
  std::vector<Vec2> points(ranges.size(), Vec2::Constant(std::numeric_limits<double>::quiet_NaN()));
  for (size_t b = 0; b < ranges.size(); ++b) {
    if (!std::isfinite(ranges[b]) || ranges[b] <= 0.0) continue;
    const double ang = fan_.BeamAngle(static_cast<int>(b));
    points[b] = ranges[b] * Vec2(std::cos(ang), std::sin(ang));
  }
  robot::SplitAndMergeParams sm;
  sm.split_m = params_.split_m;
  sm.min_points = static_cast<size_t>(params_.min_points);
  sm.min_length_m = params_.min_length_m;
  sm.max_gap_m = params_.break_base_m;
  sm.gap_per_range = params_.break_factor * fan_.step_rad;
  // The variant docs/fusion.md's figures were measured with (split_and_merge.h).
  sm.split_point_in_both = false;
  sm.merge_neighbours = false;
  sm.gap_from_farther_point = false;
  sm.clip_to_extremes = false;
  const std::vector<robot::ExtractedLine> lines = robot::SplitAndMerge(points, sm);
  for (size_t k = 0; k < lines.size() && k < 1024; ++k) {
    GroundFeature f;
    f.id = (static_cast<FeatureId>(index) << 10) | k;
    f.segment = {scan.estimated_pose.Apply(lines[k].segment.a),
                 scan.estimated_pose.Apply(lines[k].segment.b)};
    f.z_max_m = 3.0;
    // Majority vote of the beams' hits.
    std::vector<int> votes;
    for (size_t b = lines[k].first; b <= lines[k].last; ++b) votes.push_back(hits[b]);
    std::sort(votes.begin(), votes.end());
    int best = -1;
    size_t best_n = 0;
    for (size_t i = 0; i < votes.size();) {
      size_t j = i;
      while (j < votes.size() && votes[j] == votes[i]) ++j;
      if (j - i > best_n) {
        best_n = j - i;
        best = votes[i];
      }
      i = j;
    }
    scan.features.push_back(f);
    scan.truth.push_back(best);
  }
  return scan;
}

}  // namespace mapd::fusion::scenario
