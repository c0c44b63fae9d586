// The symmetries of the voxel lattice two maps of one resolution share.
//
// Every OctoMap tree of resolution r puts its voxel centres at (k + 1/2) r for
// integer k on each axis, so a rigid transform whose rotation is a signed
// permutation of the axes (one of the 24 proper rotations of the cube) and
// whose translation is whole voxels maps one map's voxel centres exactly onto
// voxel centres of the other. Such a "lattice pose" is the truth whenever a
// map is merged with a copy of itself, moved by whole voxels or turned by
// right angles. Point-to-point ICP does not find it exactly: on a lattice each
// whole-voxel shift is a local minimum of its own, and geb079.bt merged with
// itself ended 0.76 voxel off with a residual of 0.63 voxel, which resampled
// the copy across voxel borders and thickened the merged walls by half.
// voxel/merge_pair.cc tries the lattice poses around an ICP answer and keeps
// the best if it fits at least as well (issue 42 item 3).
//
// Pure functions; thread compatible.
#ifndef MAPD_VOXEL_LATTICE_POSE_H_
#define MAPD_VOXEL_LATTICE_POSE_H_

#include <Eigen/Geometry>
#include <optional>
#include <vector>

namespace mapd::voxel {

// The signed permutation matrix (det +1) nearest to the rotation R, when it is
// within max_angle_rad of R; nullopt otherwise.
std::optional<Eigen::Matrix3d> NearestLatticeRotation(const Eigen::Matrix3d& R,
                                                      double max_angle_rad);

// The lattice poses next to T for maps of voxel size voxel_m: T's rotation
// snapped by NearestLatticeRotation, and each whole-voxel translation on the
// corners of the voxel cell holding the translation that keeps `pivot` (a
// point of the source frame, metres: the middle of what is aligned) where T
// puts it. Up to 8 poses, none when the rotation is more than max_angle_rad
// from a lattice rotation or the input is not finite.
std::vector<Eigen::Isometry3d> LatticePosesNear(const Eigen::Isometry3d& T,
                                                const Eigen::Vector3d& pivot, double voxel_m,
                                                double max_angle_rad);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_LATTICE_POSE_H_
