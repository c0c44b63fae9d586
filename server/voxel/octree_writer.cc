#include <octomap/OcTree.h>

#include <sstream>

#include "voxel/octree_reader.h"

namespace mapd::voxel {

StatusOr<std::string> WriteBinaryOctree(const octomap::OcTree& tree) {
  std::stringstream out;
  if (!tree.writeBinaryConst(out)) return Status::Internal("OctoMap could not write the tree");
  return out.str();
}

}  // namespace mapd::voxel
