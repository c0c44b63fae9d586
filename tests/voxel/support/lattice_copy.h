// Exact copies of a map moved by lattice poses (right angles and whole
// voxels), and a map's voxel-for-voxel content, for the merge's exactness
// tests (issue 42 item 3). Key arithmetic only: no resampling, so a test of
// the merge never depends on the merge's own fusion to make its input.
#ifndef MAPD_TESTS_VOXEL_SUPPORT_LATTICE_COPY_H_
#define MAPD_TESTS_VOXEL_SUPPORT_LATTICE_COPY_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>

namespace mapd::testing {

// A lattice pose: voxel centre c of the input lands on rotation * c +
// shift_voxels * resolution. `rotation` must be a signed permutation (det +1).
struct LatticeMove {
  Eigen::Matrix3i rotation = Eigen::Matrix3i::Identity();
  Eigen::Vector3i shift_voxels = Eigen::Vector3i::Zero();

  // The same move as a rigid transform (metres) for maps of `resolution_m`.
  Eigen::Isometry3d Transform(double resolution_m) const;
};

// The .bt bytes of `bt` moved by `move` (every leaf expanded to voxels; dies
// on an unreadable input or one with more than max_voxels voxels).
std::string MoveByLattice(const std::string& bt, const LatticeMove& move,
                          std::uint64_t max_voxels = 30'000'000);

// Every known voxel of a .bt map: packed key -> occupied (true) or free.
using VoxelStates = std::map<std::uint64_t, bool>;
VoxelStates StatesOf(const std::string& bt, std::uint64_t max_voxels = 30'000'000);

// How `actual` differs from `expected`, in counts ("" when equal): a short
// message where EXPECT_EQ on the maps would print hundreds of voxels.
std::string DescribeDifference(const VoxelStates& actual, const VoxelStates& expected);

}  // namespace mapd::testing

#endif  // MAPD_TESTS_VOXEL_SUPPORT_LATTICE_COPY_H_
