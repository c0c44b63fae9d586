// Operator edits of an OctoMap submap (mapctl submap crop | transform): cut a
// region out of a map, or move a map by a rigid transform. Each makes a new
// tree; the input is never changed. Occupied, free and unknown stay distinct
// (free space is carried over, not dropped).
//
// Thread safety: reentrant; the functions share no state.
#ifndef MAPD_VOXEL_MAP_EDIT_H_
#define MAPD_VOXEL_MAP_EDIT_H_

#include <Eigen/Geometry>
#include <cstddef>

#include "common/status.h"
#include "voxel/octree_reader.h"

namespace mapd::voxel {

struct MapEditLimits {
  // Nodes of the output (crop: what it keeps, with the large leaves the box
  // cuts through split; transform: the voxels it sets, before pruning), at
  // kOctreeBytesPerNode each. The default, 32M nodes, is ~1.5 GiB.
  std::size_t max_output_nodes = std::size_t{32} << 20;
  // Transform: voxels of the dense box that holds the input's known voxels
  // (one byte each) and, separately, of the box probed in the output.
  std::size_t max_box_voxels = std::size_t{1} << 30;
};

// The voxels of `tree` whose centres lie in `box_m` (metres, the map's frame,
// faces included), with their states and, for a .ot tree, their log-odds;
// everything outside becomes unknown. FailedPrecondition if no known voxel
// of the map lies in the box (the message gives the map's occupied bounds),
// InvalidArgument for an empty or non-finite box, ResourceExhausted beyond
// limits.max_output_nodes.
StatusOr<OcTreePtr> CropMap(const octomap::OcTree& tree, const Eigen::AlignedBox3d& box_m,
                            const MapEditLimits& limits = {});

// The map moved by T_out_in (p_out = T_out_in * p_in), at its own
// resolution, by nearest-neighbour resampling: an output voxel takes the state
// of the input voxel that contains T_out_in^-1 * (its centre), so a rotation
// leaves no holes in surfaces, and a right-angle rotation with a translation
// of whole voxels moves every voxel exactly (no voxel gained or lost). States
// only: occupied voxels get the clamping maximum, free ones the minimum
// (log-odds are not interpolated). InvalidArgument for a transform that is
// not finite or not rigid (|det R - 1| or R's orthogonality off by > 1e-6),
// FailedPrecondition if the moved map leaves OctoMap's key range,
// ResourceExhausted beyond `limits`.
StatusOr<OcTreePtr> TransformMap(const octomap::OcTree& tree, const Eigen::Isometry3d& T_out_in,
                                 const MapEditLimits& limits = {});

// The tree as a .ot file (OctoMap write: log-odds kept).
StatusOr<std::string> WriteFullOctree(const octomap::OcTree& tree);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MAP_EDIT_H_
