#include "voxel/map_edit.h"

#include <octomap/OcTree.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "voxel/octree_leaves.h"

namespace mapd::voxel {
namespace {

constexpr int kOriginKey = 32768;    // OctoMap's key of the origin voxel
constexpr int kKeysPerAxis = 65536;  // keys per axis

using Key3 = std::array<int, 3>;  // OctoMap keys, [0, 65536)

std::string Metres(const Eigen::Vector3d& p) {
  char text[96];
  std::snprintf(text, sizeof text, "(%.2f, %.2f, %.2f)", p.x(), p.y(), p.z());
  return text;
}

// An OcTree that a crop builds node by node: OctoMap makes the root only
// when a voxel is set, and its node deletion asserts on inner nodes, so the
// crop copies what it keeps into a fresh tree instead of deleting the rest.
class BuiltTree : public octomap::OcTree {
 public:
  explicit BuiltTree(double resolution_m) : octomap::OcTree(resolution_m) {}
  octomap::OcTreeNode* MakeRoot(const octomap::OcTreeNode& like) {
    root = new octomap::OcTreeNode();
    root->copyData(like);
    tree_size = 1;
    size_changed = true;
    return root;
  }
};

// The crop's recursion: copies the voxels with keys in [lo, hi] (inclusive,
// per axis) of `src`, the cube of edge 2^level keys from `min`, into `dst`
// (made with src's value). A large leaf the box cuts through is split in the
// copy, within a budget of new nodes.
class Cropper {
 public:
  enum class Place { kOutside, kInside, kCut };

  Cropper(const octomap::OcTree& src, BuiltTree* out, const Key3& lo, const Key3& hi,
          std::size_t budget)
      : src_(src), out_(out), lo_(lo), hi_(hi), budget_(budget) {}

  Place Classify(const Key3& min, int level) const {
    const int edge = 1 << level;
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      if (min[a] > hi_[a] || min[a] + edge - 1 < lo_[a]) return Place::kOutside;
      inside = inside && min[a] >= lo_[a] && min[a] + edge - 1 <= hi_[a];
    }
    return inside ? Place::kInside : Place::kCut;
  }

  // Whether a known voxel of `src` (the cube at min, level) lies in the box.
  bool AnyKept(const octomap::OcTreeNode* src, const Key3& min, int level) const {
    const Place place = Classify(min, level);
    if (place != Place::kCut) return place == Place::kInside;
    if (!src_.nodeHasChildren(src)) return true;  // a leaf the box cuts: part of it is in
    for (unsigned i = 0; i < 8; ++i) {
      if (src_.nodeChildExists(src, i) &&
          AnyKept(src_.getNodeChild(src, i), ChildMin(min, level, i), level - 1)) {
        return true;
      }
    }
    return false;
  }

  // REQUIRES: AnyKept(src, min, level); dst holds src's value.
  void Copy(const octomap::OcTreeNode* src, octomap::OcTreeNode* dst, const Key3& min, int level) {
    const Place place = Classify(min, level);
    const bool leaf = !src_.nodeHasChildren(src);
    if (leaf && place == Place::kInside) return;
    for (unsigned i = 0; i < 8 && !exhausted_; ++i) {
      // A cut leaf stands for eight children of its own value.
      const octomap::OcTreeNode* child = src;
      if (!leaf) {
        if (!src_.nodeChildExists(src, i)) continue;
        child = src_.getNodeChild(src, i);
      }
      const Key3 child_min = ChildMin(min, level, i);
      if (place == Place::kCut && !AnyKept(child, child_min, level - 1)) continue;
      if (budget_ == 0) {
        exhausted_ = true;
        return;
      }
      --budget_;
      octomap::OcTreeNode* copy = out_->createNodeChild(dst, i);
      copy->copyData(*child);
      Copy(child, copy, child_min, level - 1);
    }
  }

  bool exhausted() const { return exhausted_; }

 private:
  // OctoMap's child index: bit 0 = x, bit 1 = y, bit 2 = z (computeChildIdx).
  static Key3 ChildMin(const Key3& min, int level, unsigned i) {
    const int half = 1 << (level - 1);
    return {min[0] + ((i & 1) ? half : 0), min[1] + ((i & 2) ? half : 0),
            min[2] + ((i & 4) ? half : 0)};
  }

  const octomap::OcTree& src_;
  BuiltTree* out_;
  const Key3 lo_, hi_;
  std::size_t budget_;
  bool exhausted_ = false;
};

std::string OccupiedBounds(const octomap::OcTree& tree) {
  Key3 lo = {kKeysPerAxis, kKeysPerAxis, kKeysPerAxis}, hi = {-1, -1, -1};
  const int max_depth = static_cast<int>(tree.getTreeDepth());
  ForEachLeaf(tree, [&](const octomap::OcTreeNode& node, const octomap::OcTreeKey& k, unsigned d) {
    if (!tree.isNodeOccupied(node)) return;
    const int level = max_depth - static_cast<int>(d);
    for (int a = 0; a < 3; ++a) {
      const int min = static_cast<int>(k[a]) >> level << level;
      lo[a] = std::min(lo[a], min);
      hi[a] = std::max(hi[a], min + (1 << level) - 1);
    }
  });
  if (hi[0] < 0) return "the map has no occupied voxel";
  const double res = tree.getResolution();
  const Eigen::Vector3d min_m((lo[0] - kOriginKey) * res, (lo[1] - kOriginKey) * res,
                              (lo[2] - kOriginKey) * res);
  const Eigen::Vector3d max_m((hi[0] + 1 - kOriginKey) * res, (hi[1] + 1 - kOriginKey) * res,
                              (hi[2] + 1 - kOriginKey) * res);
  return "the map's occupied voxels lie within " + Metres(min_m) + ".." + Metres(max_m) + " m";
}

// The input's states, dense over the box of its known leaves: the
// resampling probes every output voxel, and a tree search per probe would
// cost 16 levels.
class DenseStates {
 public:
  enum : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

  static StatusOr<DenseStates> Of(const octomap::OcTree& tree, std::size_t max_voxels) {
    DenseStates s;
    const int max_depth = static_cast<int>(tree.getTreeDepth());
    s.lo_ = {kKeysPerAxis, kKeysPerAxis, kKeysPerAxis};
    s.hi_ = {-1, -1, -1};
    const auto cube = [&](const octomap::OcTreeKey& k, unsigned d, Key3* min, int* edge) {
      const int level = max_depth - static_cast<int>(d);
      *edge = 1 << level;
      for (int a = 0; a < 3; ++a) (*min)[a] = static_cast<int>(k[a]) >> level << level;
    };
    ForEachLeaf(tree, [&](const octomap::OcTreeNode&, const octomap::OcTreeKey& k, unsigned d) {
      Key3 min;
      int edge = 0;
      cube(k, d, &min, &edge);
      for (int a = 0; a < 3; ++a) {
        s.lo_[a] = std::min(s.lo_[a], min[a]);
        s.hi_[a] = std::max(s.hi_[a], min[a] + edge - 1);
      }
    });
    if (s.hi_[0] < 0) return s;  // no known voxel
    for (int a = 0; a < 3; ++a) s.size_[a] = s.hi_[a] - s.lo_[a] + 1;
    const double voxels = static_cast<double>(s.size_[0]) * s.size_[1] * s.size_[2];
    if (voxels > static_cast<double>(max_voxels)) {
      return Status::ResourceExhausted(
          "the map's known voxels span a box of " + std::to_string(s.size_[0]) + " x " +
          std::to_string(s.size_[1]) + " x " + std::to_string(s.size_[2]) +
          " voxels, more than the " + std::to_string(max_voxels) + " a transform handles");
    }
    s.state_.assign(static_cast<std::size_t>(voxels), kUnknown);
    ForEachLeaf(tree,
                [&](const octomap::OcTreeNode& node, const octomap::OcTreeKey& k, unsigned d) {
                  Key3 min;
                  int edge = 0;
                  cube(k, d, &min, &edge);
                  const std::uint8_t state = tree.isNodeOccupied(node) ? kOccupied : kFree;
                  for (int z = min[2]; z < min[2] + edge; ++z) {
                    for (int y = min[1]; y < min[1] + edge; ++y) {
                      std::uint8_t* row = &s.state_[s.Index({min[0], y, z})];
                      std::fill(row, row + edge, state);
                    }
                  }
                });
    return s;
  }

  bool empty() const { return state_.empty(); }
  const Key3& lo() const { return lo_; }
  const Key3& hi() const { return hi_; }

  std::uint8_t At(const Key3& k) const {
    for (int a = 0; a < 3; ++a) {
      if (k[a] < lo_[a] || k[a] > hi_[a]) return kUnknown;
    }
    return state_[Index(k)];
  }

 private:
  std::size_t Index(const Key3& k) const {
    return (static_cast<std::size_t>(k[2] - lo_[2]) * size_[1] + (k[1] - lo_[1])) * size_[0] +
           (k[0] - lo_[0]);
  }

  Key3 lo_{}, hi_{}, size_{};
  std::vector<std::uint8_t> state_;
};

}  // namespace

StatusOr<OcTreePtr> CropMap(const octomap::OcTree& tree, const Eigen::AlignedBox3d& box_m,
                            const MapEditLimits& limits) {
  if (!box_m.min().allFinite() || !box_m.max().allFinite()) {
    return Status::InvalidArgument("the crop box is not finite");
  }
  if ((box_m.min().array() > box_m.max().array()).any()) {
    return Status::InvalidArgument("the crop box is empty: its minimum " + Metres(box_m.min()) +
                                   " exceeds its maximum " + Metres(box_m.max()) + " on some axis");
  }
  // A voxel is kept when its centre, (key - 32768 + 0.5) * res, is in the box.
  const double res = tree.getResolution();
  Key3 lo, hi;
  bool none = false;
  for (int a = 0; a < 3; ++a) {
    const double first = std::ceil(box_m.min()[a] / res - 0.5) + kOriginKey;
    const double last = std::floor(box_m.max()[a] / res - 0.5) + kOriginKey;
    lo[a] = static_cast<int>(std::max(first, 0.0));
    hi[a] = static_cast<int>(std::min(last, kKeysPerAxis - 1.0));
    none = none || first > kKeysPerAxis - 1.0 || last < 0.0 || lo[a] > hi[a];
  }
  auto out = std::make_unique<BuiltTree>(res);
  const octomap::OcTreeNode* root = tree.getRoot();
  const int depth = static_cast<int>(tree.getTreeDepth());
  Cropper cropper(tree, out.get(), lo, hi, limits.max_output_nodes);
  if (none || root == nullptr || !cropper.AnyKept(root, {0, 0, 0}, depth)) {
    return Status::FailedPrecondition("no known voxel of the map lies in the box " +
                                      Metres(box_m.min()) + ".." + Metres(box_m.max()) + " m; " +
                                      OccupiedBounds(tree));
  }
  cropper.Copy(root, out->MakeRoot(*root), {0, 0, 0}, depth);
  if (cropper.exhausted()) {
    return Status::ResourceExhausted("the crop would make more than " +
                                     std::to_string(limits.max_output_nodes) +
                                     " nodes (the box cuts through large cells of the map)");
  }
  out->updateInnerOccupancy();
  out->prune();
  return OcTreePtr(out.release());
}

StatusOr<OcTreePtr> TransformMap(const octomap::OcTree& tree, const Eigen::Isometry3d& T_out_in,
                                 const MapEditLimits& limits) {
  const Eigen::Matrix3d R = T_out_in.linear();
  if (!T_out_in.matrix().allFinite()) return Status::InvalidArgument("the transform is not finite");
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      std::abs(R.determinant() - 1.0) > 1e-6) {
    return Status::InvalidArgument("the transform is not rigid (its rotation is not orthonormal)");
  }
  StatusOr<DenseStates> states = DenseStates::Of(tree, limits.max_box_voxels);
  if (!states.ok()) return states.status();
  const double res = tree.getResolution();
  OcTreePtr out(new octomap::OcTree(res));
  if (states->empty()) return out;
  // The output box: the moved corners of the input box, one voxel of margin.
  Eigen::Vector3d tmin = Eigen::Vector3d::Constant(1e300), tmax = -tmin;
  for (int c = 0; c < 8; ++c) {
    Eigen::Vector3d corner;
    for (int a = 0; a < 3; ++a) {
      const int key = (c >> a) & 1 ? states->hi()[a] + 1 : states->lo()[a];
      corner[a] = (key - kOriginKey) * res;
    }
    const Eigen::Vector3d q = T_out_in * corner;
    tmin = tmin.cwiseMin(q);
    tmax = tmax.cwiseMax(q);
  }
  Key3 tlo, thi;
  double probes = 1;
  for (int a = 0; a < 3; ++a) {
    const double first = std::floor(tmin[a] / res) - 1 + kOriginKey;
    const double last = std::floor(tmax[a] / res) + 1 + kOriginKey;
    if (first < 0 || last > kKeysPerAxis - 1) {
      return Status::FailedPrecondition("the moved map would reach " +
                                        Metres(first < 0 ? tmin : tmax) +
                                        " m, outside OctoMap's key range at this resolution");
    }
    tlo[a] = static_cast<int>(first);
    thi[a] = static_cast<int>(last);
    probes *= thi[a] - tlo[a] + 1;
  }
  if (probes > static_cast<double>(limits.max_box_voxels)) {
    return Status::ResourceExhausted(
        "the moved map's box holds " + std::to_string(static_cast<std::uint64_t>(probes)) +
        " voxels, more than the " + std::to_string(limits.max_box_voxels) + " a transform handles");
  }
  const Eigen::Isometry3d T_in_out = T_out_in.inverse();
  const Eigen::Vector3d step = T_in_out.linear().col(0);  // in voxels: res cancels
  const float occupied_log_odds = out->getClampingThresMaxLog();
  const float free_log_odds = out->getClampingThresMinLog();
  std::size_t set = 0;
  // Key order (z, y, x): the same tree on every run.
  for (int z = tlo[2]; z <= thi[2]; ++z) {
    for (int y = tlo[1]; y <= thi[1]; ++y) {
      // The input position of each output centre along the row, in voxels
      // (keys minus the offset).
      const Eigen::Vector3d centre((tlo[0] - kOriginKey + 0.5) * res, (y - kOriginKey + 0.5) * res,
                                   (z - kOriginKey + 0.5) * res);
      Eigen::Vector3d p = T_in_out * centre / res;
      for (int x = tlo[0]; x <= thi[0]; ++x, p += step) {
        const Key3 source = {static_cast<int>(std::floor(p.x())) + kOriginKey,
                             static_cast<int>(std::floor(p.y())) + kOriginKey,
                             static_cast<int>(std::floor(p.z())) + kOriginKey};
        const std::uint8_t state = states->At(source);
        if (state == DenseStates::kUnknown) continue;
        if (++set > limits.max_output_nodes) {
          return Status::ResourceExhausted("the moved map has more than " +
                                           std::to_string(limits.max_output_nodes) +
                                           " known voxels to write");
        }
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(x),
                                     static_cast<octomap::key_type>(y),
                                     static_cast<octomap::key_type>(z));
        out->setNodeValue(key, state == DenseStates::kOccupied ? occupied_log_odds : free_log_odds,
                          /*lazy_eval=*/true);
      }
    }
  }
  out->updateInnerOccupancy();
  out->prune();
  return out;
}

StatusOr<std::string> WriteFullOctree(const octomap::OcTree& tree) {
  std::stringstream out;
  if (!tree.write(out)) return Status::Internal("OctoMap could not write the tree");
  return out.str();
}

}  // namespace mapd::voxel
