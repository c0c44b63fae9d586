// Placing several submaps in one frame from accepted pairwise merges
// (docs/algorithms.md B.7; the paper fuses maps c + d + e this way): the accepted
// pairs are weighted edges, a maximum spanning tree keeps the best evidence
// (Kruskal), and each submap's pose in the root's frame is the product of the
// pairwise transforms along its tree path. Pure Eigen; thread compatible.
#ifndef MAPD_VOXEL_MERGE_GRAPH_H_
#define MAPD_VOXEL_MERGE_GRAPH_H_

#include <Eigen/Geometry>
#include <vector>

namespace mapd::voxel {

// An accepted pairwise merge between nodes a and b (indices).
struct MergeEdge {
  int a = 0, b = 0;
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  // maps b's frame into a's
  double weight = 0.0;                                      // higher is better evidence
};

struct TreePlacement {
  // Per node: placed (connected to the root) and, if so, T_root_node.
  std::vector<bool> placed;
  std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>> T_root_node;
  std::vector<int> parent;  // -1 for the root and unplaced nodes
  std::vector<int> order;   // placed nodes, breadth-first from the root (root first)
};

// REQUIRES: 0 <= root < num_nodes, edge endpoints in [0, num_nodes).
// Equal weights are broken by edge order (deterministic).
TreePlacement PlaceAlongMaximumSpanningTree(int num_nodes, const std::vector<MergeEdge>& edges,
                                            int root);

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MERGE_GRAPH_H_
