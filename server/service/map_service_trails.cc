// GetTrails: each robot session's sensor positions, for the operator's view
// (mapctl trails). A read like ListRobots: the stored rows, moved into the
// map frame where the session is tied.
#include <algorithm>

#include "service/ingest_batch.h"
#include "service/map_service.h"
#include "service/status_mapping.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

constexpr uint32_t kDefaultPoses = 10000;
// A session's message stays well below gRPC's 4 MiB default (~45 bytes a pose).
constexpr uint32_t kMaxPoses = 50000;

}  // namespace

grpc::Status MapServiceImpl::GetTrails(grpc::ServerContext* context,
                                       const pb::GetTrailsRequest* request,
                                       grpc::ServerWriter<pb::SessionTrail>* writer) {
  if (auto p = AdmitToMap(*context, Permission::kReadMap, "GetTrails"); !p.ok())
    return ToGrpcStatus(p.status());
  if (!request->robot_id().empty() && !ValidId(request->robot_id())) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        "robot_id is not a robot id (1-128 chars of [A-Za-z0-9_.-])");
  }
  const uint32_t max_poses = request->max_poses_per_session() == 0
                                 ? kDefaultPoses
                                 : std::clamp(request->max_poses_per_session(), 2u, kMaxPoses);
  StatusOr<std::vector<storage::SessionTrailRows>> trails =
      core_->store().ListTrails(request->robot_id(), max_poses);
  if (!trails.ok()) return ToGrpcStatus(trails.status());
  for (const storage::SessionTrailRows& t : *trails) {
    // The tie as now stored; a session tied later is drawn in the map frame from then on.
    StatusOr<storage::SessionFrame> frame = core_->store().GetSession(t.session_id);
    const bool tied = frame.ok() && frame->tied;
    pb::SessionTrail out;
    out.set_robot_id(t.robot);
    out.set_session_id(t.session);
    out.set_frame_tied(tied);
    out.set_stored_poses(t.stored);
    for (const storage::TrailPoint& p : t.points) {
      const Eigen::Vector3d position = tied ? frame->T_map_frame * p.position : p.position;
      pb::TrailPose* pose = out.add_poses();
      pose->set_seq(p.seq);
      pose->set_stamp_ns(p.stamp_ns);
      pose->mutable_position()->set_x(position.x());
      pose->mutable_position()->set_y(position.y());
      pose->mutable_position()->set_z(position.z());
    }
    if (!writer->Write(out)) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
  }
  return grpc::Status::OK;
}

}  // namespace mapd::service
