// Rendering of server answers for people and for other tools. Pure functions:
// no I/O, no gRPC calls; every one returns the whole text.
//
// Coordinates are map-frame metres throughout (the fused map's frame), not
// geographic longitude/latitude.
#ifndef MAPD_CLIENT_FORMAT_H_
#define MAPD_CLIENT_FORMAT_H_

#include <google/protobuf/message.h>

#include <string>
#include <vector>

#include "geometry/rigid3.h"
#include "mapserver/v1/map_service.pb.h"

namespace mapd::client {

using FeatureList = std::vector<mapserver::v1::FusedFeature>;
// Fused non-vertical planes (floors, ceilings, ramps): FeatureMapPage.planes.
using PlaneList = std::vector<mapserver::v1::FusedPlane>;

enum class OutputFormat { kTable, kJson, kGeoJson, kSvg };

// "table", "json", "geojson", "svg" -> format; false for anything else.
bool ParseOutputFormat(const std::string& name, OutputFormat* out);
// From a file name's extension (.json, .geojson, .svg); `fallback` otherwise.
OutputFormat GuessOutputFormat(const std::string& path, OutputFormat fallback);
// Whether the name ends in .json, .geojson, .svg, or .txt (a table).
bool HasOutputExtension(const std::string& path);

// Any message in the protobuf JSON mapping, with the .proto field names
// (snake_case), default values printed and two-space indentation, except that
// 64-bit integers are numbers ("batches": 120; the mapping writes strings), as
// in every other JSON mapctl writes.
std::string MessageToJson(const google::protobuf::Message& message);

// One line per feature with a header, then a count; then, if there are
// planes, one line per plane (id, normal, offset, area, z range, support,
// robots) and their count.
std::string FormatFeatureTable(const FeatureList& features, const PlaneList& planes = {});
// A FeatureMapPage holding every feature and plane, as protobuf JSON, with
// the server's map_version and fusion_pending (acknowledged batches the map
// did not reflect yet when it was read).
std::string FormatFeatureJson(const FeatureList& features, uint64_t map_version,
                              const PlaneList& planes = {}, uint64_t fusion_pending = 0);
// A GeoJSON FeatureCollection: one LineString per feature (properties id,
// kind, support, member_count, z_min, z_max, robots), then one Polygon per
// plane: the ground projection (x, y) of its boundary, counter-clockwise for
// an upward normal; properties id, kind "plane", normal [x, y, z], offset_m,
// area_m2, z_min, z_max, support, member_count, robots.
std::string FormatGeoJson(const FeatureList& features, const PlaneList& planes = {});

// `mapctl trails`: a GeoJSON FeatureCollection, one LineString per robot
// session through its sensor positions (x, y; a Point for a single pose);
// properties robot_id, session_id, frame ("map" where the session is tied,
// else "session": its own frame), poses (in the line), stored_poses,
// first_stamp_ns, last_stamp_ns. Sessions without a pose are left out.
std::string FormatTrailsGeoJson(const std::vector<mapserver::v1::SessionTrail>& trails);

// `mapctl status` for people.
std::string FormatStats(const mapserver::v1::Stats& stats, const std::string& server);
// `mapctl robots` table; `now_ns` (server clock) makes "last seen 3 s ago".
std::string FormatRobots(const mapserver::v1::ListRobotsResponse& robots, int64_t now_ns);
// `mapctl submaps` table.
std::string FormatSubmaps(const mapserver::v1::ListSubmapsResponse& submaps);

// Stored merges (client/format_merges.cc). "proposed", "accepted",
// "rejected", "refused" ("unknown" otherwise).
std::string MergeStateName(mapserver::v1::MergeState state);
// `mapctl merges`: one line per merge (inputs, merged map, the weakest
// input's corners / residual / overlap, who asked, when, who decided, reason).
std::string FormatMerges(const mapserver::v1::ListMergesResponse& merges);
// The same as JSON (nlohmann-json, snake_case keys, 64-bit ids as numbers):
// {"merges": [{"id", "state", "inputs": [{"submap_id", "aligned",
// "t_reference_submap": {"translation", "rotation_wxyz"}, "yaw_pitch_roll_deg",
// "matched_corners", "residual_m", "overlap_score", "matched": [{"in_submap":
// [x, y, z], "in_reference": [x, y, z]}] (empty from ListMerges)}], "merged_submap_id",
// "reason", "requested_by", "created_ns", "decided_by", "decided_ns"}]}.
std::string FormatMergesJson(const mapserver::v1::ListMergesResponse& merges);
// One merge as above (`mapctl merge show --json`).
std::string FormatMergeRecordJson(const mapserver::v1::MergeRecord& merge);
// `mapctl merge show`: state, who and when, reason, per input its transform
// (xyz, yaw/pitch/roll in degrees), evidence and the first 5 matched corner
// pairs (with their count).
std::string FormatMergeRecord(const mapserver::v1::MergeRecord& merge);
// One line (newline-ended): where an input sits in the reference frame (xyz
// in metres, yaw/pitch/roll in degrees) and its matched corners, residual
// and overlap; "not aligned" for an input of a refused merge.
std::string FormatAlignment(const mapserver::v1::SubmapAlignment& alignment);
// The API's transform as the client's (for renderings and yaw/pitch/roll).
geometry::Rigid3 ToRigid3(const mapserver::v1::Rigid3& T);

// `mapctl watch`: one line per change of a FeatureMapDelta (a resync first
// gets its own line, "resync"). Text: `v=<map_version> <added|updated|removed>
// feature|plane <id> ...`. JSON lines (json = true): {"map_version", "change":
// "resync"|"added"|"updated"|"removed", "type": "feature"|"plane", "id", and
// for added/updated the feature's or plane's fields in snake_case}.
std::string FormatDeltaLines(const mapserver::v1::FeatureMapDelta& delta, bool json);

// "line", "plane" or "any".
std::string KindName(mapserver::v1::FeatureKind kind);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_FORMAT_H_
