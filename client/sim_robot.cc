#include "client/sim_robot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

double Distance(const Point2& p, const Point2& q) { return std::hypot(p.x - q.x, p.y - q.y); }

// Distance from p to the infinite line through a and b (a != b).
double DistanceToLine(const Point2& p, const Point2& a, const Point2& b) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double len = std::hypot(dx, dy);
  if (len < 1e-12) return Distance(p, a);
  return std::abs(dx * (p.y - a.y) - dy * (p.x - a.x)) / len;
}

// Ray from `o` along unit `d` against segment s: distance to the hit, or +inf.
double RayHit(const Point2& o, const Point2& d, const Segment2& s) {
  const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
  const double denom = d.x * ey - d.y * ex;  // cross(d, e)
  if (std::abs(denom) < 1e-12) return std::numeric_limits<double>::infinity();
  const double wx = s.a.x - o.x, wy = s.a.y - o.y;
  const double t = (wx * ey - wy * ex) / denom;  // along the ray
  const double u = (wx * d.y - wy * d.x) / denom;  // along the segment
  if (t <= 0 || u < 0 || u > 1) return std::numeric_limits<double>::infinity();
  return t;
}

double BeamAngle(int i, const LaserParams& laser) {
  return -laser.fov_rad / 2 + i * laser.fov_rad / std::max(1, laser.beams - 1);
}

// Total-least-squares line through points[i..j], returned as the segment
// between the projections of the first and the last point.
Segment2 FitSegment(const std::vector<Point2>& points, size_t i, size_t j) {
  const double n = static_cast<double>(j - i + 1);
  double mx = 0, my = 0;
  for (size_t k = i; k <= j; ++k) {
    mx += points[k].x;
    my += points[k].y;
  }
  mx /= n;
  my /= n;
  double sxx = 0, syy = 0, sxy = 0;
  for (size_t k = i; k <= j; ++k) {
    const double dx = points[k].x - mx, dy = points[k].y - my;
    sxx += dx * dx;
    syy += dy * dy;
    sxy += dx * dy;
  }
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);  // principal direction
  const double ux = std::cos(angle), uy = std::sin(angle);
  auto project = [&](const Point2& p) {
    const double t = (p.x - mx) * ux + (p.y - my) * uy;
    return Point2{mx + t * ux, my + t * uy};
  };
  return {project(points[i]), project(points[j])};
}

double MaxDistanceToFit(const std::vector<Point2>& points, size_t i, size_t j) {
  const Segment2 fit = FitSegment(points, i, j);
  double worst = 0;
  for (size_t k = i; k <= j; ++k) worst = std::max(worst, DistanceToLine(points[k], fit.a, fit.b));
  return worst;
}

// The split step: index ranges [i, j] whose points all lie within the
// threshold of the chord p_i p_j.
void Split(const std::vector<Point2>& points, size_t i, size_t j, double threshold,
           std::vector<std::pair<size_t, size_t>>* out) {
  double worst = 0;
  size_t worst_k = i;
  for (size_t k = i + 1; k < j; ++k) {
    const double d = DistanceToLine(points[k], points[i], points[j]);
    if (d > worst) {
      worst = d;
      worst_k = k;
    }
  }
  if (worst <= threshold) {
    out->emplace_back(i, j);
    return;
  }
  Split(points, i, worst_k, threshold, out);
  Split(points, worst_k, j, threshold, out);
}

}  // namespace

SimWorld DefaultWorld() {
  SimWorld w;
  auto wall = [&w](double ax, double ay, double bx, double by) {
    w.walls.push_back({{ax, ay}, {bx, by}});
  };
  // Outer walls of the 20 m x 12 m floor.
  wall(0, 0, 20, 0);
  wall(20, 0, 20, 12);
  wall(20, 12, 0, 12);
  wall(0, 12, 0, 0);
  // Interior wall stubs, outside the robot loop.
  wall(7, 0, 7, 2);     // from the bottom wall
  wall(13, 12, 13, 10); // from the top wall
  wall(0, 6, 2.5, 6);   // from the left wall
  wall(20, 4, 18, 4);   // from the right wall
  // A box in the middle of the loop.
  wall(9, 5.25, 11, 5.25);
  wall(11, 5.25, 11, 6.75);
  wall(11, 6.75, 9, 6.75);
  wall(9, 6.75, 9, 5.25);
  w.loop = {{4, 3}, {16, 3}, {16, 9}, {4, 9}};  // counter-clockwise, 36 m
  return w;
}

double DistanceToSegment(const Point2& p, const Segment2& s) {
  const double ex = s.b.x - s.a.x, ey = s.b.y - s.a.y;
  const double len2 = ex * ex + ey * ey;
  if (len2 < 1e-24) return Distance(p, s.a);
  const double t = std::clamp(((p.x - s.a.x) * ex + (p.y - s.a.y) * ey) / len2, 0.0, 1.0);
  return Distance(p, {s.a.x + t * ex, s.a.y + t * ey});
}

std::vector<double> CastScan(const std::vector<Segment2>& walls, const Pose2& T_map_sensor,
                             const LaserParams& laser, std::mt19937_64* rng) {
  std::normal_distribution<double> noise(0.0, laser.range_noise_m);
  std::vector<double> ranges(static_cast<size_t>(std::max(0, laser.beams)));
  const Point2 origin{T_map_sensor.x, T_map_sensor.y};
  for (int i = 0; i < laser.beams; ++i) {
    const double angle = T_map_sensor.yaw + BeamAngle(i, laser);
    const Point2 dir{std::cos(angle), std::sin(angle)};
    double nearest = std::numeric_limits<double>::infinity();
    for (const Segment2& w : walls) nearest = std::min(nearest, RayHit(origin, dir, w));
    // Draw the noise for every beam so the random stream does not depend on hits.
    const double r = nearest + noise(*rng);
    ranges[static_cast<size_t>(i)] =
        nearest <= laser.max_range_m ? r : std::numeric_limits<double>::quiet_NaN();
  }
  return ranges;
}

std::vector<Segment2> ExtractSegments(const std::vector<double>& ranges, const LaserParams& laser,
                                      const ExtractionParams& params) {
  const double beam_spacing = laser.fov_rad / std::max(1, laser.beams - 1);
  std::vector<Segment2> segments;
  const size_t min_points = static_cast<size_t>(std::max(2, params.min_points));

  // Runs of consecutive valid beams without a jump between neighbours.
  std::vector<Point2> run;
  double last_range = 0;
  auto flush = [&]() {
    if (run.size() >= min_points) {
      std::vector<std::pair<size_t, size_t>> pieces;
      Split(run, 0, run.size() - 1, params.split_threshold_m, &pieces);
      // Merge step: neighbouring pieces that fit one line together become one.
      std::vector<std::pair<size_t, size_t>> merged;
      for (const auto& piece : pieces) {
        if (!merged.empty() && merged.back().second == piece.first &&
            MaxDistanceToFit(run, merged.back().first, piece.second) <= params.split_threshold_m) {
          merged.back().second = piece.second;
        } else {
          merged.push_back(piece);
        }
      }
      for (const auto& [i, j] : merged) {
        if (j - i + 1 < min_points) continue;
        const Segment2 s = FitSegment(run, i, j);
        if (Distance(s.a, s.b) >= params.min_length_m) segments.push_back(s);
      }
    }
    run.clear();
  };
  for (size_t i = 0; i < ranges.size(); ++i) {
    const double r = ranges[i];
    if (!std::isfinite(r) || r <= 0) {
      flush();
      continue;
    }
    const double angle = BeamAngle(static_cast<int>(i), laser);
    const Point2 p{r * std::cos(angle), r * std::sin(angle)};
    if (!run.empty()) {
      const double gap = std::max(params.min_gap_m, params.gap_factor * std::max(r, last_range) * beam_spacing);
      if (Distance(p, run.back()) > gap) flush();
    }
    run.push_back(p);
    last_range = r;
  }
  flush();
  return segments;
}

SimRobot::SimRobot(SimWorld world, SimRobotParams params)
    : world_(std::move(world)), params_(std::move(params)), rng_(params_.seed) {
  const size_t n = world_.loop.size();
  for (size_t i = 0; i < n; ++i) loop_length_m_ += Distance(world_.loop[i], world_.loop[(i + 1) % n]);
  double start = params_.start_fraction - std::floor(params_.start_fraction);
  travelled_m_ = start * loop_length_m_;
}

Pose2 SimRobot::pose() const { return PoseAt(travelled_m_); }

Pose2 SimRobot::PoseAt(double distance_m) const {
  const size_t n = world_.loop.size();
  if (n < 2 || loop_length_m_ <= 0) return n == 1 ? Pose2{world_.loop[0].x, world_.loop[0].y, 0} : Pose2{};
  double d = std::fmod(distance_m, loop_length_m_);
  if (d < 0) d += loop_length_m_;
  for (size_t i = 0; i < n; ++i) {
    const Point2& a = world_.loop[i];
    const Point2& b = world_.loop[(i + 1) % n];
    const double len = Distance(a, b);
    if (d <= len || i + 1 == n) {
      const double t = len > 0 ? std::min(d / len, 1.0) : 0;
      return {a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), std::atan2(b.y - a.y, b.x - a.x)};
    }
    d -= len;
  }
  return {};
}

pb::ObservationBatch SimRobot::NextBatch() {
  const Pose2 p = pose();
  const std::vector<double> ranges = CastScan(world_.walls, p, params_.laser, &rng_);
  const std::vector<Segment2> segments = ExtractSegments(ranges, params_.laser, params_.extraction);

  pb::ObservationBatch batch;
  batch.set_robot_id(params_.robot_id);
  batch.set_session_id(params_.session_id);
  batch.set_seq(params_.first_seq + scans_);
  batch.set_stamp_ns(params_.start_stamp_ns + static_cast<int64_t>(scans_) * params_.scan_period_ns);
  batch.set_session_frame(pb::SESSION_FRAME_MAP);
  pb::Rigid3* T_frame_sensor = batch.mutable_t_frame_sensor();
  T_frame_sensor->mutable_translation()->set_x(p.x);
  T_frame_sensor->mutable_translation()->set_y(p.y);
  T_frame_sensor->mutable_translation()->set_z(0);
  T_frame_sensor->mutable_rotation()->set_w(std::cos(p.yaw / 2));
  T_frame_sensor->mutable_rotation()->set_z(std::sin(p.yaw / 2));
  for (const Segment2& s : segments) {
    pb::LineSegment* line = batch.add_lines();
    line->mutable_a()->set_x(s.a.x);
    line->mutable_a()->set_y(s.a.y);
    line->mutable_b()->set_x(s.b.x);
    line->mutable_b()->set_y(s.b.y);
  }
  travelled_m_ += params_.step_m;
  ++scans_;
  return batch;
}

}  // namespace mapd::client
