// ForEachLeaf: every leaf of an OctoMap tree, as OcTree's leaf_iterator gives
// them (the same leaves, keys, depths and order), by plain recursion.
//
// Why not the iterator: it keeps an explicit std::stack (a deque) of 24-byte
// elements and pushes every inner node's children through it. The fusion
// walks both maps and VoxelGrid::FromOcTree walks each map twice; collecting
// a campus crop's ~520k leaves for the fusion took 0.13 s through the
// iterator, 0.10 s with this (docs/archive/voxel-merge-history.md, "Leaf walks by recursion").
//
// Thread safety: reentrant; reads the tree only.
#ifndef MAPD_VOXEL_OCTREE_LEAVES_H_
#define MAPD_VOXEL_OCTREE_LEAVES_H_

#include <octomap/OcTree.h>

namespace mapd::voxel {
namespace internal {

template <typename Visit>
void VisitLeaves(const octomap::OcTree& tree, const octomap::OcTreeNode* node,
                 const octomap::OcTreeKey& key, unsigned depth, unsigned max_depth, Visit& visit) {
  if (depth == max_depth || !tree.nodeHasChildren(node)) {
    visit(*node, key, depth);
    return;
  }
  // The iterator's child keys: the parent's key moved by the child's half
  // edge (in keys) along each axis; children in index order 0..7.
  const auto center_offset_key = static_cast<octomap::key_type>(32768 >> (depth + 1));
  octomap::OcTreeKey child_key;
  for (unsigned i = 0; i < 8; ++i) {
    if (!tree.nodeChildExists(node, i)) continue;
    octomap::computeChildKey(i, center_offset_key, key, child_key);
    VisitLeaves(tree, tree.getNodeChild(node, i), child_key, depth + 1, max_depth, visit);
  }
}

}  // namespace internal

// Calls visit(const OcTreeNode& leaf, const OcTreeKey& key, unsigned depth)
// for every leaf (a node without children, or at the tree's depth), in
// leaf_iterator's order, with its key and depth (root = 0; a leaf of depth d
// is a cube of 2^(tree depth - d) voxels). The recursion is as deep as the
// tree (16 levels at most: OctoMap's keys are 16 bits).
template <typename Visit>
void ForEachLeaf(const octomap::OcTree& tree, Visit&& visit) {
  const octomap::OcTreeNode* root = tree.getRoot();
  if (root == nullptr) return;
  // leaf_iterator's root key: tree_max_val (32768) on every axis.
  const octomap::OcTreeKey root_key(32768, 32768, 32768);
  internal::VisitLeaves(tree, root, root_key, 0, tree.getTreeDepth(), visit);
}

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_OCTREE_LEAVES_H_
