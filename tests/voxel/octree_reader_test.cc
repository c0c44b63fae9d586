// The safe .bt/.ot reader (voxel/octree_reader.h): round trips, hostile and
// truncated input, limits, and the real maps of the shared data directory
// read like OctoMap reads them.
#include "voxel/octree_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "voxel/support/hostile_bt.h"
#include "voxel/voxel_grid.h"

namespace mapd::voxel {
namespace {

using ::testing::HasSubstr;

// The shared data directory: $MAPD_SHARED_DIR/data (ctest sets
// MAPD_SHARED_DIR to ../shared), /work/shared/data when it is not set.
std::string SharedDataDir() {
  const char* dir = std::getenv("MAPD_SHARED_DIR");
  return std::string(dir != nullptr ? dir : "/work/shared") + "/data";
}

// Whether the real maps can be looked for at all. A developer without the
// shared folder skips them (the tests say why); where the directory is, a
// listed map that is missing fails: a map renamed or not fetched must not
// turn a test into a silent pass.
bool HaveSharedData() { return std::filesystem::is_directory(SharedDataDir()); }
std::string NoSharedDataReason() {
  return "no shared data directory " + SharedDataDir() +
         " (set MAPD_SHARED_DIR to the folder holding data/octomap/): real maps not read";
}

std::string SharedOctomap(const std::string& name) { return SharedDataDir() + "/octomap/" + name; }

bool FileExists(const std::string& path) { return std::ifstream(path).good(); }

using mapd::testing::BtChain;
using mapd::testing::BtHeader;

// A small real tree written by OctoMap itself: a box surface, some free space.
octomap::OcTree MakeTree() {
  octomap::OcTree tree(0.1);
  for (int x = 0; x < 20; ++x) {
    for (int y = 0; y < 12; ++y) {
      tree.updateNode(octomap::point3d(0.1f * x + 0.05f, 0.1f * y + 0.05f, 0.05f), true);
      tree.updateNode(octomap::point3d(0.1f * x + 0.05f, 0.1f * y + 0.05f, 1.05f), false);
    }
  }
  for (int z = 0; z < 8; ++z) {
    tree.updateNode(octomap::point3d(-0.35f, 0.25f, 0.1f * z + 0.05f), true);
  }
  return tree;
}

std::string WriteBt(octomap::OcTree& tree) {
  std::ostringstream out;
  tree.writeBinary(out);
  return out.str();
}

std::string WriteOt(const octomap::OcTree& tree) {
  std::ostringstream out;
  tree.write(out);
  return out.str();
}

std::size_t OccupiedLeaves(const octomap::OcTree& tree) {
  std::size_t n = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) n += tree.isNodeOccupied(*it);
  return n;
}

Status ErrorOf(const std::string& bytes, const OctreeReadLimits& limits = {}) {
  return ReadOctree(bytes, limits).status();
}

TEST(OctreeReaderTest, ReadsRealMapsLikeOctoMap) {
  const struct {
    const char* name;
    double resolution;
  } maps[] = {{"geb079.bt", 0.08}, {"fr_078_tidyup.bt", 0.05}, {"new_college.bt", 0.2}};
  if (!HaveSharedData()) GTEST_SKIP() << NoSharedDataReason();
  for (const auto& map : maps) {
    const std::string path = SharedOctomap(map.name);
    if (!FileExists(path)) {
      ADD_FAILURE() << path << " is missing from the shared data directory";
      continue;
    }
    StatusOr<OcTreePtr> ours = ReadOctreeFile(path);
    ASSERT_TRUE(ours.ok()) << ours.status().ToString();
    octomap::OcTree theirs(path);  // trusted file: OctoMap's own reader
    EXPECT_DOUBLE_EQ((*ours)->getResolution(), map.resolution) << map.name;
    EXPECT_EQ((*ours)->size(), theirs.size()) << map.name;
    EXPECT_EQ(OccupiedLeaves(**ours), OccupiedLeaves(theirs)) << map.name;
    EXPECT_GT(OccupiedLeaves(theirs), 0u);
  }
}

TEST(OctreeReaderTest, RoundTripsBothFormats) {
  octomap::OcTree tree = MakeTree();
  const std::string bt = WriteBt(tree);
  const std::string ot = WriteOt(tree);
  for (const std::string* bytes : {&bt, &ot}) {
    StatusOr<OcTreePtr> read = ReadOctree(*bytes);
    ASSERT_TRUE(read.ok()) << read.status().ToString();
    EXPECT_EQ((*read)->size(), tree.size());
    EXPECT_EQ(OccupiedLeaves(**read), OccupiedLeaves(tree));
  }
  StatusOr<OctreeSummary> summary = ValidateOctree(ot);
  ASSERT_TRUE(summary.ok());
  EXPECT_EQ(summary->format, OctreeFormat::kFull);
  EXPECT_EQ(summary->max_depth, 16);
}

TEST(OctreeReaderTest, ReadsEmptyTree) {
  octomap::OcTree empty(0.25);
  for (const std::string& bytes : {WriteBt(empty), WriteOt(empty)}) {
    StatusOr<OcTreePtr> read = ReadOctree(bytes);
    ASSERT_TRUE(read.ok()) << read.status().ToString();
    EXPECT_EQ((*read)->size(), 0u);
    EXPECT_DOUBLE_EQ((*read)->getResolution(), 0.25);
  }
}

TEST(OctreeReaderTest, RefusesTruncatedInput) {
  octomap::OcTree tree = MakeTree();
  for (const std::string& bytes : {WriteBt(tree), WriteOt(tree)}) {
    const std::size_t data = ValidateOctree(bytes)->data_offset;
    for (std::size_t keep : {data - 3, data, data + 1, data + 2, data + 7,
                             (data + bytes.size()) / 2, bytes.size() - 1}) {
      const Status status = ErrorOf(bytes.substr(0, keep));
      EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << keep;
      if (keep >= data) {
        EXPECT_THAT(status.message(), HasSubstr("truncated after " + std::to_string(keep) + " of"));
      }
    }
  }
}

TEST(OctreeReaderTest, RefusesTrailingGarbage) {
  octomap::OcTree tree = MakeTree();
  for (const std::string& bytes : {WriteBt(tree), WriteOt(tree)}) {
    const Status status = ErrorOf(bytes + "xyz");
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
    EXPECT_THAT(status.message(), HasSubstr("3 trailing bytes"));
  }
  EXPECT_THAT(ErrorOf(BtHeader("0", "0.1") + "x").message(), HasSubstr("trailing"));
}

TEST(OctreeReaderTest, RefusesDeepChainQuicklyWithoutRecursion) {
  const std::string chain = BtChain(100'000);  // 200 KB
  const auto start = std::chrono::steady_clock::now();
  const Status status = ErrorOf(chain);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("tree deeper than 16 levels"));
  EXPECT_LT(seconds, 0.1);
}

TEST(OctreeReaderTest, AcceptsSixteenLevelsRefusesSeventeen) {
  StatusOr<OcTreePtr> sixteen = ReadOctree(BtChain(16));
  ASSERT_TRUE(sixteen.ok()) << sixteen.status().ToString();
  EXPECT_EQ(OccupiedLeaves(**sixteen), 1u);
  EXPECT_THAT(ErrorOf(BtChain(17)).message(), HasSubstr("tree deeper than 16 levels"));

  // The same in the .ot format: 17 nodes on a chain are fine, 18 are not.
  auto ot_chain = [](int nodes) {
    std::string bytes =
        "# Octomap OcTree file\nid OcTree\nsize " + std::to_string(nodes) + "\nres 0.1\ndata\n";
    const float log_odds = 1.0f;
    for (int i = 0; i < nodes; ++i) {
      bytes.append(reinterpret_cast<const char*>(&log_odds), sizeof(log_odds));
      bytes += (i + 1 < nodes) ? '\x01' : '\x00';
    }
    return bytes;
  };
  EXPECT_TRUE(ReadOctree(ot_chain(17)).ok());
  EXPECT_THAT(ErrorOf(ot_chain(18)).message(), HasSubstr("tree deeper than 16 levels"));
  EXPECT_THAT(ErrorOf(ot_chain(100'000)).message(), HasSubstr("tree deeper than 16 levels"));
}

TEST(OctreeReaderTest, RefusesHugeSizeBeforeAllocating) {
  const Status huge = ErrorOf(BtHeader("4000000000", "0.1") + std::string(64, '\xff'));
  EXPECT_EQ(huge.code(), StatusCode::kResourceExhausted);
  EXPECT_THAT(huge.message(), HasSubstr("header claims 4000000000 nodes"));
  EXPECT_EQ(ErrorOf(BtHeader("99999999999", "0.1")).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ErrorOf(BtHeader("-1", "0.1")).code(), StatusCode::kInvalidArgument);

  // A complete tree (every record "8 inner children") of 4.8 MB would make
  // OctoMap allocate ~800 MB; a small max_bytes refuses it by node count.
  OctreeReadLimits limits;
  limits.max_bytes = 1 << 20;
  const Status complete = ErrorOf(BtHeader("19000000", "0.1") + std::string(1000, '\xff'), limits);
  EXPECT_EQ(complete.code(), StatusCode::kResourceExhausted);
  // Within the node limit, but the size does not match the tree.
  EXPECT_THAT(ErrorOf(BtHeader("2", "0.1") + std::string(4, '\xff')).message(),
              HasSubstr("more nodes than the header's size 2"));
  EXPECT_THAT(ErrorOf(BtHeader("5", "0.1") + std::string("\x02\x00", 2)).message(),
              HasSubstr("header says size 5 but the tree has 2 nodes"));
  // Input larger than max_bytes.
  limits.max_bytes = 16;
  EXPECT_EQ(ErrorOf(BtChain(3), limits).code(), StatusCode::kResourceExhausted);
}

TEST(OctreeReaderTest, RefusesBadResolution) {
  const std::string leaf("\x02\x00", 2);
  EXPECT_THAT(ErrorOf(BtHeader("2", "nan") + leaf).message(), HasSubstr("resolution is NaN"));
  EXPECT_THAT(ErrorOf(BtHeader("2", "inf") + leaf).message(), HasSubstr("infinite"));
  EXPECT_THAT(ErrorOf(BtHeader("2", "-0.1") + leaf).message(), HasSubstr("not positive"));
  EXPECT_THAT(ErrorOf(BtHeader("2", "0") + leaf).message(), HasSubstr("not positive"));
  EXPECT_THAT(ErrorOf(BtHeader("2", "0.1cm") + leaf).message(), HasSubstr("not a number"));
  EXPECT_THAT(ErrorOf(BtHeader("2", "1e300") + leaf).message(), HasSubstr("implausibly large"));
  EXPECT_TRUE(ReadOctree(BtHeader("2", "0.1") + leaf).ok());
}

TEST(OctreeReaderTest, RefusesGarbageHeaders) {
  EXPECT_THAT(ErrorOf("").message(), HasSubstr("empty input"));
  EXPECT_THAT(ErrorOf(std::string(5000, '\x17')).message(), HasSubstr("not an octree file"));
  EXPECT_THAT(ErrorOf("PK\x03\x04 hello\n\n").message(), HasSubstr("not an octree file"));
  const std::string magic = "# Octomap OcTree binary file\n";
  EXPECT_THAT(ErrorOf(magic + "id OcTree\nsize 1\nres 0.1\n").message(), HasSubstr("no 'data'"));
  EXPECT_THAT(ErrorOf(magic + "id ColorOcTree\nsize 1\nres 0.1\ndata\n").message(),
              HasSubstr("not supported"));
  EXPECT_THAT(ErrorOf(magic + "size 1\nres 0.1\ndata\n").message(), HasSubstr("no 'id'"));
  EXPECT_THAT(ErrorOf(magic + "id OcTree\nres 0.1\ndata\n").message(), HasSubstr("no 'size'"));
  EXPECT_THAT(ErrorOf(magic + "id OcTree\nsize 1\ndata\n").message(), HasSubstr("no 'res'"));
  EXPECT_THAT(ErrorOf(magic + "id OcTree\nsize 1\nres 0.1\nres 0.2\ndata\n").message(),
              HasSubstr("twice"));
  EXPECT_THAT(ErrorOf(magic + "id OcTree\nfoo 3\nsize 1\nres 0.1\ndata\n").message(),
              HasSubstr("unknown keyword 'foo'"));
  // A header that never ends.
  EXPECT_THAT(ErrorOf(magic + std::string(100'000, '#')).message(), HasSubstr("no 'data' line"));
}

TEST(OctreeReaderTest, RefusesStructuralOddities) {
  // An inner node with no children (OctoMap would give it log-odds -FLT_MAX).
  EXPECT_THAT(ErrorOf(BtHeader("2", "0.1") + std::string("\x03\x00\x00\x00", 4)).message(),
              HasSubstr("has no children"));
  // A non-finite log-odds value in a .ot file.
  std::string ot = "# Octomap OcTree file\nid OcTree\nsize 1\nres 0.1\ndata\n";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  ot.append(reinterpret_cast<const char*>(&nan), sizeof(nan));
  ot += '\0';
  EXPECT_THAT(ErrorOf(ot).message(), HasSubstr("non-finite log-odds"));
}

TEST(OctreeReaderTest, MissingFileIsNotFound) {
  EXPECT_EQ(ReadOctreeFile("/nonexistent/map.bt").status().code(), StatusCode::kNotFound);
}

}  // namespace
}  // namespace mapd::voxel

namespace mapd::voxel {
namespace {

// The walk's voxel counts and bounds (what an upload is summarised and capped
// by, without building a tree) equal what OctoMap and VoxelGrid build.
void ExpectWalkMatchesTree(const std::string& bytes, const std::string& what) {
  StatusOr<OctreeSummary> walk = ValidateOctree(bytes);
  ASSERT_TRUE(walk.ok()) << what << ": " << walk.status().ToString();
  StatusOr<OcTreePtr> tree = ReadOctree(bytes);
  ASSERT_TRUE(tree.ok()) << what;
  StatusOr<VoxelGrid> grid = VoxelGrid::FromOcTree(**tree);
  ASSERT_TRUE(grid.ok()) << what;
  EXPECT_EQ(walk->occupied_voxels, grid->num_occupied()) << what;
  uint64_t free_voxels = 0;
  for (auto it = (*tree)->begin_leafs(); it != (*tree)->end_leafs(); ++it) {
    if (!(*tree)->isNodeOccupied(*it))
      free_voxels += uint64_t{1} << (3 * (16 - static_cast<int>(it.getDepth())));
  }
  EXPECT_EQ(walk->free_voxels, free_voxels) << what;
  if (!grid->empty()) {
    for (int a = 0; a < 3; ++a) {
      EXPECT_EQ(walk->occupied_min_key[a], grid->min_key()[a]) << what << " axis " << a;
      EXPECT_EQ(walk->occupied_max_key[a], grid->max_key()[a]) << what << " axis " << a;
    }
  }
}

TEST(OctreeReaderTest, WalkCountsVoxelsLikeTheBuiltGrid) {
  octomap::OcTree tree = MakeTree();
  tree.prune();  // coarse leaves: one leaf stands for many voxels
  ExpectWalkMatchesTree(WriteBt(tree), "generated .bt");
  ExpectWalkMatchesTree(WriteOt(tree), "generated .ot");
}

// The same on the real maps (their own test, so that the generated trees
// above are checked without the shared data too).
TEST(OctreeReaderTest, WalkCountsVoxelsLikeTheBuiltGridOnRealMaps) {
  if (!HaveSharedData()) GTEST_SKIP() << NoSharedDataReason();
  for (const char* name : {"geb079.bt", "fr_078_tidyup.bt"}) {
    const std::string path = SharedOctomap(name);
    if (!FileExists(path)) {
      ADD_FAILURE() << path << " is missing from the shared data directory";
      continue;
    }
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    ExpectWalkMatchesTree(s.str(), name);
  }
}

TEST(OctreeReaderTest, RefusesATinyFileThatExpandsBeyondTheVoxelCap) {
  // Root plus one occupied leaf at depth 1: 8^15 voxels from 61 bytes.
  std::string bt = "# Octomap OcTree binary file\nid OcTree\nsize 2\nres 0.1\ndata\n";
  bt += std::string("\x02\x00", 2);
  OctreeReadLimits limits;
  limits.max_occupied_voxels = 1000;
  const Status s = ValidateOctree(bt, limits).status();
  EXPECT_EQ(s.code(), StatusCode::kResourceExhausted) << s.ToString();
  EXPECT_THAT(s.message(), ::testing::HasSubstr("occupied voxels"));
  limits.max_occupied_voxels = 0;  // no limit: valid, and counted exactly
  StatusOr<OctreeSummary> summary = ValidateOctree(bt, limits);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->occupied_voxels, uint64_t{1} << 45);
}

}  // namespace
}  // namespace mapd::voxel
