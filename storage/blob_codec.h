// The byte layouts of the small blobs every backend stores the same way:
// a fused plane's boundary, a merge input's matched corner pairs and the
// global map's member list. Backend-neutral (no SQL).
#ifndef MAPD_STORAGE_BLOB_CODEC_H_
#define MAPD_STORAGE_BLOB_CODEC_H_

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "storage/submap_store.h"

namespace mapd::storage {

// x, y, z doubles per point, little-endian (the machine's order).
std::string EncodeBoundary(const std::vector<Eigen::Vector3d>& boundary);
// Internal naming fused plane `id` when the blob is not whole points.
Status DecodeBoundary(std::string_view blob, uint64_t id, std::vector<Eigen::Vector3d>* out);

// Six doubles per pair: in_submap xyz, in_reference xyz.
std::string EncodeMatched(const std::vector<MatchedCornerRecord>& matched);
// Internal naming merge `merge_id` when the blob is not whole pairs.
Status DecodeMatched(std::string_view blob, int64_t merge_id,
                     std::vector<MatchedCornerRecord>* out);

// "id qw qx qy qz tx ty tz" per line, %.17g: doubles round-trip exactly, so a
// member read back compares equal to the pose it was fused at.
std::string EncodeMembers(const std::vector<GlobalMapMember>& members);
StatusOr<std::vector<GlobalMapMember>> DecodeMembers(const std::string& text);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_BLOB_CODEC_H_
