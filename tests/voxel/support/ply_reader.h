// Reads the vertex positions of a PLY file (ascii or binary_little_endian;
// x, y, z as float/float32 or double/float64; other scalar vertex properties
// are skipped). Test support: enough for the TEASER++ benchmark sets.
#ifndef MAPD_TESTS_VOXEL_SUPPORT_PLY_READER_H_
#define MAPD_TESTS_VOXEL_SUPPORT_PLY_READER_H_

#include <Eigen/Core>
#include <string>
#include <vector>

#include "common/status.h"

namespace mapd::testing {

StatusOr<std::vector<Eigen::Vector3d>> ReadPlyVertices(const std::string& path);

}  // namespace mapd::testing

#endif  // MAPD_TESTS_VOXEL_SUPPORT_PLY_READER_H_
