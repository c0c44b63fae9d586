#include "storage/blob_codec.h"

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <sstream>

namespace mapd::storage {

// The boundary as x, y, z doubles in the machine's (little-endian) byte order.
std::string EncodeBoundary(const std::vector<Eigen::Vector3d>& boundary) {
  std::string out(boundary.size() * 3 * sizeof(double), '\0');
  char* p = out.data();
  for (const Eigen::Vector3d& v : boundary) {
    std::memcpy(p, v.data(), 3 * sizeof(double));
    p += 3 * sizeof(double);
  }
  return out;
}

Status DecodeBoundary(std::string_view blob, uint64_t id, std::vector<Eigen::Vector3d>* out) {
  if (blob.size() % (3 * sizeof(double)) != 0) {
    return Status::Internal("fused_planes row " + std::to_string(id) + ": boundary blob of " +
                            std::to_string(blob.size()) + " bytes is not a list of 3D points");
  }
  out->resize(blob.size() / (3 * sizeof(double)));
  for (size_t i = 0; i < out->size(); ++i) {
    std::memcpy((*out)[i].data(), blob.data() + i * 3 * sizeof(double), 3 * sizeof(double));
  }
  return Status::Ok();
}

// merge_inputs.matched_points (schema.cc, 6 -> 7).
constexpr size_t kMatchedPointBytes = 6 * sizeof(double);

std::string EncodeMatched(const std::vector<MatchedCornerRecord>& matched) {
  std::string out(matched.size() * kMatchedPointBytes, '\0');
  char* p = out.data();
  for (const MatchedCornerRecord& m : matched) {
    std::memcpy(p, m.in_submap.data(), 3 * sizeof(double));
    std::memcpy(p + 3 * sizeof(double), m.in_reference.data(), 3 * sizeof(double));
    p += kMatchedPointBytes;
  }
  return out;
}

Status DecodeMatched(std::string_view blob, int64_t merge_id,
                     std::vector<MatchedCornerRecord>* out) {
  if (blob.size() % kMatchedPointBytes != 0) {
    return Status::Internal("merge " + std::to_string(merge_id) + ": matched_points blob of " +
                            std::to_string(blob.size()) + " bytes is not whole corner pairs");
  }
  out->resize(blob.size() / kMatchedPointBytes);
  for (size_t i = 0; i < out->size(); ++i) {
    const char* p = blob.data() + i * kMatchedPointBytes;
    std::memcpy((*out)[i].in_submap.data(), p, 3 * sizeof(double));
    std::memcpy((*out)[i].in_reference.data(), p + 3 * sizeof(double), 3 * sizeof(double));
  }
  return Status::Ok();
}

// "id qw qx qy qz tx ty tz" per line, %.17g: doubles round-trip exactly, so a
// member read back compares equal to the pose it was fused at.
std::string EncodeMembers(const std::vector<GlobalMapMember>& members) {
  std::string out;
  char line[256];
  for (const GlobalMapMember& m : members) {
    const geometry::Rigid3& T = m.T_map_submap;
    std::snprintf(line, sizeof line, "%" PRId64 " %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  m.submap_id, T.rotation.w(), T.rotation.x(), T.rotation.y(), T.rotation.z(),
                  T.translation.x(), T.translation.y(), T.translation.z());
    out += line;
  }
  return out;
}

StatusOr<std::vector<GlobalMapMember>> DecodeMembers(const std::string& text) {
  std::vector<GlobalMapMember> members;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    GlobalMapMember m;
    double q[4], t[3];
    if (std::sscanf(line.c_str(), "%" SCNd64 " %lf %lf %lf %lf %lf %lf %lf", &m.submap_id, &q[0],
                    &q[1], &q[2], &q[3], &t[0], &t[1], &t[2]) != 8) {
      return Status::Internal("global_map.members is corrupt: '" + line + "'");
    }
    m.T_map_submap.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
    m.T_map_submap.translation = {t[0], t[1], t[2]};
    members.push_back(m);
  }
  return members;
}

}  // namespace mapd::storage
