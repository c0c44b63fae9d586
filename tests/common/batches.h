// Observation batches for tests: a robot in a rectangular room reporting the
// room's walls as line segments in its sensor frame.
#ifndef MAPD_TESTS_COMMON_BATCHES_H_
#define MAPD_TESTS_COMMON_BATCHES_H_

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "mapserver/v1/map_service.pb.h"

namespace mapd::testing {

struct Wall {
  Eigen::Vector2d a, b;  // map frame, metres
};

// A 10 m x 8 m room with its corner at the origin.
inline std::vector<Wall> RoomWalls() {
  return {{{0, 0}, {10, 0}}, {{10, 0}, {10, 8}}, {{10, 8}, {0, 8}}, {{0, 8}, {0, 0}}};
}

inline void SetVec3(const Eigen::Vector3d& v, mapserver::v1::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

// A batch seen from (x, y, yaw): each wall as one segment covering 80-95% of
// it, endpoints jittered by `noise_m`, expressed in the sensor frame.
inline mapserver::v1::ObservationBatch RoomBatch(const std::string& robot,
                                                 const std::string& session, uint64_t seq, double x,
                                                 double y, double yaw, std::mt19937_64* rng,
                                                 double noise_m = 0.01) {
  std::uniform_real_distribution<double> trim(0.02, 0.1);
  std::normal_distribution<double> noise(0.0, noise_m);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d t(x, y, 0);
  mapserver::v1::ObservationBatch batch;
  batch.set_robot_id(robot);
  batch.set_session_id(session);
  batch.set_seq(seq);
  batch.set_stamp_ns(static_cast<int64_t>(seq) * 100000000);
  auto* pose = batch.mutable_t_frame_sensor();
  SetVec3(t, pose->mutable_translation());
  pose->mutable_rotation()->set_w(q.w());
  pose->mutable_rotation()->set_x(q.x());
  pose->mutable_rotation()->set_y(q.y());
  pose->mutable_rotation()->set_z(q.z());
  for (const Wall& w : RoomWalls()) {
    const Eigen::Vector2d d = w.b - w.a;
    const Eigen::Vector2d a = w.a + trim(*rng) * d + Eigen::Vector2d(noise(*rng), noise(*rng));
    const Eigen::Vector2d b = w.b - trim(*rng) * d + Eigen::Vector2d(noise(*rng), noise(*rng));
    auto* line = batch.add_lines();
    SetVec3(q.inverse() * (Eigen::Vector3d(a.x(), a.y(), 0) - t), line->mutable_a());
    SetVec3(q.inverse() * (Eigen::Vector3d(b.x(), b.y(), 0) - t), line->mutable_b());
  }
  return batch;
}

// Batches re-expressed in a robot's own session frame (SESSION_FRAME_LOCAL) whose pose in
// the map frame is T_map_b: the same walls seen from the same places, another frame.
inline std::vector<mapserver::v1::ObservationBatch> InFrame(
    std::vector<mapserver::v1::ObservationBatch> batches, const Eigen::Isometry3d& T_map_b) {
  const Eigen::Isometry3d T_b_map = T_map_b.inverse();
  for (mapserver::v1::ObservationBatch& batch : batches) {
    auto* pose = batch.mutable_t_frame_sensor();
    const Eigen::Quaterniond q(pose->rotation().w(), pose->rotation().x(), pose->rotation().y(),
                               pose->rotation().z());
    const Eigen::Vector3d t(pose->translation().x(), pose->translation().y(),
                            pose->translation().z());
    const Eigen::Quaterniond q_b(T_b_map.rotation() * q.toRotationMatrix());
    const Eigen::Vector3d t_b = T_b_map * t;
    SetVec3(t_b, pose->mutable_translation());
    pose->mutable_rotation()->set_w(q_b.w());
    pose->mutable_rotation()->set_x(q_b.x());
    pose->mutable_rotation()->set_y(q_b.y());
    pose->mutable_rotation()->set_z(q_b.z());
    batch.set_session_frame(mapserver::v1::SESSION_FRAME_LOCAL);
  }
  return batches;
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_COMMON_BATCHES_H_
