#include "voxel/merge_graph.h"

#include <algorithm>
#include <numeric>
#include <queue>

namespace mapd::voxel {
namespace {

int Find(std::vector<int>* parent, int x) {
  while ((*parent)[static_cast<std::size_t>(x)] != x) {
    (*parent)[static_cast<std::size_t>(x)] =
        (*parent)[static_cast<std::size_t>((*parent)[static_cast<std::size_t>(x)])];
    x = (*parent)[static_cast<std::size_t>(x)];
  }
  return x;
}

}  // namespace

TreePlacement PlaceAlongMaximumSpanningTree(int num_nodes, const std::vector<MergeEdge>& edges,
                                            int root) {
  const auto n = static_cast<std::size_t>(num_nodes);
  // Kruskal on descending weight.
  std::vector<int> by_weight(edges.size());
  std::iota(by_weight.begin(), by_weight.end(), 0);
  std::stable_sort(by_weight.begin(), by_weight.end(), [&](int x, int y) {
    return edges[static_cast<std::size_t>(x)].weight > edges[static_cast<std::size_t>(y)].weight;
  });
  std::vector<int> set(n);
  std::iota(set.begin(), set.end(), 0);
  std::vector<std::vector<int>> tree_edges(n);  // edge indices per node
  for (int e : by_weight) {
    const MergeEdge& edge = edges[static_cast<std::size_t>(e)];
    const int ra = Find(&set, edge.a), rb = Find(&set, edge.b);
    if (ra == rb) continue;
    set[static_cast<std::size_t>(ra)] = rb;
    tree_edges[static_cast<std::size_t>(edge.a)].push_back(e);
    tree_edges[static_cast<std::size_t>(edge.b)].push_back(e);
  }
  // Breadth-first from the root, composing the transforms.
  TreePlacement out;
  out.placed.assign(n, false);
  out.T_root_node.assign(n, Eigen::Isometry3d::Identity());
  out.parent.assign(n, -1);
  std::queue<int> queue;
  queue.push(root);
  out.placed[static_cast<std::size_t>(root)] = true;
  while (!queue.empty()) {
    const int node = queue.front();
    queue.pop();
    out.order.push_back(node);
    for (int e : tree_edges[static_cast<std::size_t>(node)]) {
      const MergeEdge& edge = edges[static_cast<std::size_t>(e)];
      const int other = edge.a == node ? edge.b : edge.a;
      if (out.placed[static_cast<std::size_t>(other)]) continue;
      // T_node_other is T_a_b when node is a, its inverse when node is b.
      const Eigen::Isometry3d T_node_other = edge.a == node ? edge.T_a_b : edge.T_a_b.inverse();
      out.T_root_node[static_cast<std::size_t>(other)] =
          out.T_root_node[static_cast<std::size_t>(node)] * T_node_other;
      out.parent[static_cast<std::size_t>(other)] = node;
      out.placed[static_cast<std::size_t>(other)] = true;
      queue.push(other);
    }
  }
  return out;
}

}  // namespace mapd::voxel
