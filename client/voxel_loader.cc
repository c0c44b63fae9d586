#include "client/voxel_loader.h"

#include <iostream>
#include <streambuf>

#include "voxel/octree_reader.h"

namespace mapd::client {
namespace {

// Debian's OctoMap is built with its debug messages on: its reader writes
// "Reading binary octree type OcTree" to std::cerr on every file. mapctl's
// stderr carries one line per error, so the reader runs with std::cerr
// silenced (mapctl is single-threaded; errors come back as Status, not text).
class SilenceCerr {
 public:
  SilenceCerr() : saved_(std::cerr.rdbuf(&null_)) {}
  ~SilenceCerr() { std::cerr.rdbuf(saved_); }
  SilenceCerr(const SilenceCerr&) = delete;
  SilenceCerr& operator=(const SilenceCerr&) = delete;

 private:
  struct NullBuffer : std::streambuf {
    int overflow(int c) override { return traits_type::not_eof(c); }
  };
  NullBuffer null_;
  std::streambuf* saved_;
};

}  // namespace

StatusOr<voxel::VoxelGrid> LoadVoxelGrid(std::string_view bytes) {
  StatusOr<voxel::OcTreePtr> tree = [&] {
    SilenceCerr quiet;
    return voxel::ReadOctree(bytes);
  }();
  if (!tree.ok()) return tree.status();
  return voxel::VoxelGrid::FromOcTree(**tree);
}

StatusOr<LoadedVoxels> LoadOccupiedVoxels(std::string_view bytes) {
  StatusOr<voxel::VoxelGrid> grid = LoadVoxelGrid(bytes);
  if (!grid.ok()) return grid.status();
  LoadedVoxels out;
  out.resolution_m = grid->resolution();
  out.centres_m.reserve(grid->occupied_centres().size());
  for (const Eigen::Vector3d& c : grid->occupied_centres()) out.centres_m.push_back(c);
  return out;
}

}  // namespace mapd::client
