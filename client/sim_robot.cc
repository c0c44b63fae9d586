#include "client/sim_robot.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "client/robot/laser_lines.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

// The laser's beams: a fan from -fov/2 to +fov/2 with both ends included.
sim::LaserFan Fan(const LaserParams& laser) {
  sim::LaserFan fan;
  fan.start_rad = -laser.fov_rad / 2;
  fan.step_rad = laser.fov_rad / std::max(1, laser.beams - 1);
  fan.beams = std::max(0, laser.beams);
  fan.max_range_m = laser.max_range_m;
  return fan;
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
  wall(7, 0, 7, 2);      // from the bottom wall
  wall(13, 12, 13, 10);  // from the top wall
  wall(0, 6, 2.5, 6);    // from the left wall
  wall(20, 4, 18, 4);    // from the right wall
  // A box in the middle of the loop.
  wall(9, 5.25, 11, 5.25);
  wall(11, 5.25, 11, 6.75);
  wall(11, 6.75, 9, 6.75);
  wall(9, 6.75, 9, 5.25);
  w.loop = {{4, 3}, {16, 3}, {16, 9}, {4, 9}};  // counter-clockwise, 36 m
  return w;
}

std::vector<double> CastScan(const std::vector<Segment2>& walls, const Pose2& T_map_sensor,
                             const LaserParams& laser, std::mt19937_64* rng) {
  std::normal_distribution<double> noise(0.0, laser.range_noise_m);
  std::vector<double> ranges = sim::CastLaser(walls, T_map_sensor, Fan(laser)).range_m;
  for (double& r : ranges) {
    // Draw the noise for every beam so the random stream does not depend on hits.
    const double n = noise(*rng);
    r = std::isfinite(r) ? r + n : std::numeric_limits<double>::quiet_NaN();
  }
  return ranges;
}

std::vector<Segment2> ExtractSegments(const std::vector<double>& ranges, const LaserParams& laser,
                                      const ExtractionParams& params) {
  // The robot library's extractor, as a real robot would call it.
  const sim::LaserFan fan = Fan(laser);
  robot::LaserScan scan;
  scan.angle_min_rad = fan.start_rad;
  scan.angle_increment_rad = fan.step_rad;
  scan.range_max_m = 100'000.0;  // noise may carry a return past max_range_m: kept
  scan.ranges_m = ranges;
  robot::LineExtractionParams lines;
  lines.split_m = params.split_threshold_m;
  lines.min_points = std::max(2, params.min_points);
  lines.min_length_m = params.min_length_m;
  lines.max_gap_m = params.min_gap_m;
  lines.gap_per_range = params.gap_factor * fan.step_rad;
  // The settings are the simulator's own; a scan of no beams has no lines.
  const auto extracted = robot::ExtractLines(scan, lines);
  std::vector<Segment2> segments;
  if (!extracted.ok()) return segments;
  for (const robot::ExtractedLine& line : *extracted) segments.push_back(line.segment);
  return segments;
}

SimRobot::SimRobot(SimWorld world, SimRobotParams params)
    : world_(std::move(world)), params_(std::move(params)), rng_(params_.seed) {
  const size_t n = world_.loop.size();
  for (size_t i = 0; i < n; ++i)
    loop_length_m_ += (world_.loop[(i + 1) % n] - world_.loop[i]).norm();
  double start = params_.start_fraction - std::floor(params_.start_fraction);
  travelled_m_ = start * loop_length_m_;
}

Pose2 SimRobot::pose() const { return PoseAt(travelled_m_); }

Pose2 SimRobot::PoseAt(double distance_m) const {
  const size_t n = world_.loop.size();
  if (n < 2 || loop_length_m_ <= 0) return n == 1 ? Pose2{world_.loop[0], 0} : Pose2{};
  double d = std::fmod(distance_m, loop_length_m_);
  if (d < 0) d += loop_length_m_;
  for (size_t i = 0; i < n; ++i) {
    const Vec2& a = world_.loop[i];
    const Vec2& b = world_.loop[(i + 1) % n];
    const double len = (b - a).norm();
    if (d <= len || i + 1 == n) {
      const double t = len > 0 ? std::min(d / len, 1.0) : 0;
      return {a + t * (b - a), std::atan2(b.y() - a.y(), b.x() - a.x())};
    }
    d -= len;
  }
  return {};
}

pb::ObservationBatch SimRobot::NextBatch() {
  if (params_.has_change && !changed_ &&
      driven_m_ >= params_.change.after_laps * loop_length_m_ - 1e-9) {
    changed_ = true;
    std::vector<Segment2> walls;
    for (size_t i = 0; i < world_.walls.size(); ++i) {
      const auto& gone = params_.change.remove;
      if (std::find(gone.begin(), gone.end(), i) == gone.end()) walls.push_back(world_.walls[i]);
    }
    walls.insert(walls.end(), params_.change.add.begin(), params_.change.add.end());
    world_.walls = std::move(walls);
  }
  const Pose2 p = pose();
  const std::vector<double> ranges = CastScan(world_.walls, p, params_.laser, &rng_);
  const std::vector<Segment2> segments = ExtractSegments(ranges, params_.laser, params_.extraction);

  pb::ObservationBatch batch;
  batch.set_robot_id(params_.robot_id);
  batch.set_session_id(params_.session_id);
  batch.set_seq(params_.first_seq + scans_);
  batch.set_stamp_ns(params_.start_stamp_ns +
                     static_cast<int64_t>(scans_) * params_.scan_period_ns);
  batch.set_session_frame(pb::SESSION_FRAME_MAP);
  pb::Rigid3* T_frame_sensor = batch.mutable_t_frame_sensor();
  const Eigen::Quaterniond q(Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()));
  T_frame_sensor->mutable_translation()->set_x(p.t.x());
  T_frame_sensor->mutable_translation()->set_y(p.t.y());
  T_frame_sensor->mutable_translation()->set_z(0);
  T_frame_sensor->mutable_rotation()->set_w(q.w());
  T_frame_sensor->mutable_rotation()->set_z(q.z());
  for (const Segment2& s : segments) {
    pb::LineSegment* line = batch.add_lines();
    line->mutable_a()->set_x(s.a.x());
    line->mutable_a()->set_y(s.a.y());
    line->mutable_b()->set_x(s.b.x());
    line->mutable_b()->set_y(s.b.y());
  }
  travelled_m_ += params_.step_m;
  driven_m_ += params_.step_m;
  ++scans_;
  return batch;
}

}  // namespace mapd::client
