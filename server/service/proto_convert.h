// Conversions between the libraries' types and the API's messages that more
// than one handler needs. (Requests are checked and converted where they
// arrive, ingest_batch.h, map_service.cc, watch_service.cc, from the pieces
// below.)
#ifndef MAPD_SERVICE_PROTO_CONVERT_H_
#define MAPD_SERVICE_PROTO_CONVERT_H_

#include <Eigen/Core>

#include "geometry/rigid3.h"
#include "mapserver/v1/map_service.pb.h"
#include "service/core.h"
#include "storage/store.h"

namespace mapd::service {

void ToProto(const Eigen::Vector3d& v, mapserver::v1::Vec3* out);
void ToProto(const geometry::Rigid3& T, mapserver::v1::Rigid3* out);
void ToProto(const storage::SubmapMeta& m, mapserver::v1::SubmapInfo* out);
// GetFeatureMap and WatchFeatureMap.
void ToProto(const FusedView& v, mapserver::v1::FusedFeature* out);
void ToProto(const PlaneView& v, mapserver::v1::FusedPlane* out);

// The filters GetFeatureMap and WatchFeatureMap share. InvalidArgument naming
// the field: a non-finite or inverted box, an unknown kind.
Status FromProto(const mapserver::v1::BoundingBox2& in, geometry::Box2* out);
Status FromProto(mapserver::v1::FeatureKind in, KindFilter* out);

}  // namespace mapd::service

#endif  // MAPD_SERVICE_PROTO_CONVERT_H_
