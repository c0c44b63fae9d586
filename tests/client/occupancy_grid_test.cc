// The ROS occupancy grid cut from a voxel map (client/occupancy_grid.h), on
// the shared OctoMap room (common/octomap_scenes.h) and on hand-made octrees:
// walls where the scene has walls, free where it is free, the orientation
// map_server expects (row 0 = largest y), the YAML fields and the errors.
#include "client/occupancy_grid.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <sstream>

#include "common/octomap_scenes.h"
#include "voxel/octree_reader.h"

namespace mapd::client {
namespace {

using ::testing::HasSubstr;

voxel::VoxelGrid GridOf(const std::string& bt) {
  StatusOr<voxel::OcTreePtr> tree = voxel::ReadOctree(bt);
  EXPECT_TRUE(tree.ok()) << tree.status().ToString();
  StatusOr<voxel::VoxelGrid> grid = voxel::VoxelGrid::FromOcTree(**tree);
  EXPECT_TRUE(grid.ok()) << grid.status().ToString();
  return *grid;
}

Cell At(const OccupancyGrid& g, double x, double y) {
  int col = 0, row = 0;
  EXPECT_TRUE(g.CellOf(x, y, &col, &row)) << x << ", " << y;
  return g.at(col, row);
}

class OccupancyGridRoomTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // The whole 10 m x 8 m room (walls on its four sides, furniture, free inside).
    room_ = new voxel::VoxelGrid(
        GridOf(testing::RoomSubmap(testing::RoomScene(), 0, 10, Eigen::Isometry3d::Identity())));
  }
  static void TearDownTestSuite() {
    delete room_;
    room_ = nullptr;
  }
  static voxel::VoxelGrid* room_;
};

voxel::VoxelGrid* OccupancyGridRoomTest::room_ = nullptr;

TEST_F(OccupancyGridRoomTest, WallsAreOccupiedAndTheRoomIsFree) {
  StatusOr<OccupancyGrid> g = BuildOccupancyGrid(*room_, OccupancyGridOptions());
  ASSERT_TRUE(g.ok()) << g.status().ToString();
  EXPECT_EQ(g->width, 100);
  EXPECT_EQ(g->height, 80);
  EXPECT_NEAR(g->resolution_m, 0.1, 1e-12);
  EXPECT_NEAR(g->origin_x_m, 0.0, 1e-9);
  EXPECT_NEAR(g->origin_y_m, 0.0, 1e-9);
  for (int col = 0; col < g->width; ++col) {
    EXPECT_EQ(g->at(col, 0), Cell::kOccupied) << col;              // y = 8 wall: the top row
    EXPECT_EQ(g->at(col, g->height - 1), Cell::kOccupied) << col;  // y = 0 wall
  }
  for (int row = 0; row < g->height; ++row) {
    EXPECT_EQ(g->at(0, row), Cell::kOccupied) << row;
    EXPECT_EQ(g->at(g->width - 1, row), Cell::kOccupied) << row;
  }
  // Open floor between the furniture, and a box (1.0-2.2 x 1.0-1.6 m, 0.8 m high).
  EXPECT_EQ(At(*g, 7.05, 1.05), Cell::kFree);
  EXPECT_EQ(At(*g, 0.55, 7.45), Cell::kFree);
  EXPECT_EQ(At(*g, 1.55, 1.25), Cell::kOccupied);
  // The side of a tall box at y 5.5-6.1 (upper half) shows there, not mirrored at y 1.9-2.5.
  // (Its inside is unknown: the shell hides it, and its top is above the band.)
  EXPECT_EQ(At(*g, 5.25, 5.85), Cell::kOccupied);
  EXPECT_EQ(At(*g, 5.55, 5.85), Cell::kUnknown);
  EXPECT_EQ(At(*g, 5.25, 8.0 - 5.85), Cell::kFree);
  int col = 0, row = 0;
  ASSERT_TRUE(g->CellOf(5.25, 5.85, &col, &row));
  EXPECT_LT(row, g->height / 2);  // upper half of the map = upper half of the image
  size_t free = 0;
  for (Cell c : g->cells) free += c == Cell::kFree ? 1 : 0;
  EXPECT_GT(free, g->cells.size() / 2);
}

TEST_F(OccupancyGridRoomTest, BandThroughTheFloorOccupiesEveryCellAndAboveTheRoomIsRefused) {
  OccupancyGridOptions floor;
  floor.z_min_m = 0.0;
  floor.z_max_m = 0.09;  // the floor layer's centres are at 0.05 m
  StatusOr<OccupancyGrid> g = BuildOccupancyGrid(*room_, floor);
  ASSERT_TRUE(g.ok()) << g.status().ToString();
  for (Cell c : g->cells) ASSERT_EQ(c, Cell::kOccupied);

  OccupancyGridOptions above;
  above.z_min_m = 3.0;
  above.z_max_m = 4.0;
  g = BuildOccupancyGrid(*room_, above);
  ASSERT_FALSE(g.ok());
  EXPECT_EQ(g.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(g.status().message(), HasSubstr("no occupied voxel between z 3 and 4 m"));
  EXPECT_THAT(g.status().message(), HasSubstr("span z 0 to 2.5"));
}

TEST_F(OccupancyGridRoomTest, BadBandAndResolutionAreRefused) {
  OccupancyGridOptions o;
  o.z_min_m = 1.0;
  o.z_max_m = 0.5;
  StatusOr<OccupancyGrid> g = BuildOccupancyGrid(*room_, o);
  EXPECT_EQ(g.status().code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(g.status().message(), HasSubstr("--z-min"));
  o.z_min_m = 0.51;  // between two layers' centres (0.45, 0.55)
  o.z_max_m = 0.54;
  g = BuildOccupancyGrid(*room_, o);
  EXPECT_EQ(g.status().code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(g.status().message(), HasSubstr("holds no voxel centre"));
  o = OccupancyGridOptions();
  o.resolution_m = -1;
  EXPECT_EQ(BuildOccupancyGrid(*room_, o).status().code(), StatusCode::kInvalidArgument);
  o = OccupancyGridOptions();
  o.resolution_m = 0.001;  // 10,000 x 8,000 cells
  o.max_cells = 1'000'000;
  g = BuildOccupancyGrid(*room_, o);
  EXPECT_EQ(g.status().code(), StatusCode::kResourceExhausted);
  EXPECT_THAT(g.status().message(), HasSubstr("coarser --resolution"));
}

TEST_F(OccupancyGridRoomTest, CoarserCellsAndLinesBeyondTheMap) {
  OccupancyGridOptions o;
  o.resolution_m = 0.2;
  // A fused wall 2 m beyond the room's x = 10 side grows the grid to hold it.
  const std::vector<GridLine> lines = {{12.05, 1.0, 12.05, 7.0}};
  StatusOr<OccupancyGrid> g = BuildOccupancyGrid(*room_, o, lines);
  ASSERT_TRUE(g.ok()) << g.status().ToString();
  EXPECT_NEAR(g->resolution_m, 0.2, 1e-12);
  EXPECT_EQ(g->width, 61);  // [0, 12.2)
  EXPECT_EQ(g->height, 40);
  EXPECT_EQ(At(*g, 12.05, 4.0), Cell::kOccupied);
  EXPECT_EQ(At(*g, 11.0, 4.0), Cell::kUnknown);  // outside the room: never seen
  EXPECT_EQ(At(*g, 7.1, 1.1), Cell::kFree);
  EXPECT_EQ(At(*g, 9.95, 4.0), Cell::kOccupied);
}

// A wall along the top (largest y) of a free patch, off the origin: its rows
// are the image's first rows, and the origin is the lower-left corner.
TEST(OccupancyGridTest, WallAtMaxYIsInTheTopRows) {
  octomap::OcTree tree(0.1);
  for (int i = 0; i < 30; ++i) {
    const float x = -2.0f + 0.1f * i + 0.05f;
    for (int k = 2; k < 15; ++k) tree.updateNode(x, 2.95f, 0.1f * k + 0.05f, true);
    for (int j = 0; j < 20; ++j)
      for (int k = 2; k < 15; ++k)
        tree.updateNode(x, 0.9f + 0.1f * j + 0.05f, 0.1f * k + 0.05f, false);
  }
  std::ostringstream bt;
  tree.writeBinary(bt);
  StatusOr<OccupancyGrid> g = BuildOccupancyGrid(GridOf(bt.str()), OccupancyGridOptions());
  ASSERT_TRUE(g.ok()) << g.status().ToString();
  EXPECT_EQ(g->width, 30);
  EXPECT_EQ(g->height, 21);  // y 0.9 .. 3.0
  EXPECT_NEAR(g->origin_x_m, -2.0, 1e-6);
  EXPECT_NEAR(g->origin_y_m, 0.9, 1e-6);
  for (int col = 0; col < g->width; ++col) {
    EXPECT_EQ(g->at(col, 0), Cell::kOccupied);
    for (int row = 1; row < g->height; ++row) ASSERT_EQ(g->at(col, row), Cell::kFree) << row;
  }

  // The files: P5 with the top row first; map_server's YAML.
  const std::string pgm = EncodePgm(*g);
  const std::string header = "P5\n30 21\n255\n";
  ASSERT_EQ(pgm.size(), header.size() + 30 * 21);
  EXPECT_EQ(pgm.substr(0, header.size()), header);
  EXPECT_EQ(static_cast<unsigned char>(pgm[header.size()]), 0);         // top-left: the wall
  EXPECT_EQ(static_cast<unsigned char>(pgm[header.size() + 30]), 254);  // second row: free
  EXPECT_EQ(EncodeMapYaml(*g, "floor.pgm"),
            "image: floor.pgm\nmode: trinary\nresolution: 0.1\norigin: [-2, 0.9, 0.0]\nnegate: "
            "0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
}

TEST(OccupancyGridTest, UnknownCellsAre205) {
  OccupancyGrid g;
  g.resolution_m = 0.5;
  g.width = 2;
  g.height = 1;
  g.cells = {Cell::kUnknown, Cell::kFree};
  const std::string pgm = EncodePgm(g);
  EXPECT_EQ(static_cast<unsigned char>(pgm[pgm.size() - 2]), 205);
  EXPECT_EQ(static_cast<unsigned char>(pgm[pgm.size() - 1]), 254);
}

}  // namespace
}  // namespace mapd::client
