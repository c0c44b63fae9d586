// GET /api/robots: every robot with its counts, its last pose and a short
// trail (the newest session's last kTrail poses, one index read each).
// Poses are in the map frame when that session is tied to it; a session in
// its own frame (not merged yet) has "frame": "local" and is not drawn.
#include <cmath>

#include "web/http_util.h"
#include "web/web_json.h"

namespace mapd::web {
namespace {

constexpr int kTrail = 60;

Json PoseJson(const geometry::Rigid3& T, const storage::StampedPose& p) {
  const Eigen::Vector3d x = T.rotation * Eigen::Vector3d::UnitX();
  return {{"x", T.translation.x()},          {"y", T.translation.y()}, {"z", T.translation.z()},
          {"yaw", std::atan2(x.y(), x.x())}, {"stamp_ns", p.stamp_ns}, {"seq", p.seq}};
}

}  // namespace

void ServeRobots(service::Core* core, httplib::Response& res) {
  storage::Store& store = core->store();
  StatusOr<std::vector<storage::RobotSummary>> robots = store.ListRobots();
  if (!robots.ok()) return SendError(res, robots.status());
  StatusOr<std::vector<storage::SessionFrame>> sessions = store.ListSessions();
  if (!sessions.ok()) return SendError(res, sessions.status());
  Json out = Json::array();
  for (const storage::RobotSummary& r : *robots) {
    Json robot = {{"robot_id", r.name},
                  {"sessions", r.sessions},
                  {"batches", r.batches},
                  {"features", r.features},
                  {"first_seen_ns", r.first_seen_ns},
                  {"last_seen_ns", r.last_seen_ns}};
    const storage::SessionFrame* newest = nullptr;
    for (const storage::SessionFrame& s : *sessions) {
      if (s.robot_id == r.id && (newest == nullptr || s.session_id > newest->session_id))
        newest = &s;
    }
    if (newest != nullptr) {
      StatusOr<std::vector<storage::StampedPose>> poses =
          store.RecentPoses(newest->session_id, kTrail);
      if (!poses.ok()) return SendError(res, poses.status());
      const bool in_map = newest->kind == storage::FrameKind::kMap || newest->tied;
      Json trail = Json::array();
      for (const storage::StampedPose& p : *poses) {
        const geometry::Rigid3 T =
            newest->tied ? newest->T_map_frame * p.T_frame_sensor : p.T_frame_sensor;
        if (trail.empty()) robot["pose"] = PoseJson(T, p);
        trail.push_back({T.translation.x(), T.translation.y()});
      }
      robot["frame"] = in_map ? "map" : "local";
      robot["trail"] = std::move(trail);  // newest first
    }
    out.push_back(std::move(robot));
  }
  res.set_content(Dump({{"robots", std::move(out)}}), "application/json");
}

}  // namespace mapd::web
