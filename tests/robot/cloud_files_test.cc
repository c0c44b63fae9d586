// Point cloud files: an organised PCD stays organised and gives the room's
// planes, a PLY's, a KITTI .bin's and a text file's points are unorganised (a dense room)
// and give them too, and a bad file is named (with its line, for text) without a crash.
#include "client/robot/cloud_files.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <fstream>
#include <string>

#include "client/robot/pcl_cloud.h"
#include "common/temp_dir.h"
#include "robot/room_scan.h"

namespace mapd::robot {
namespace {

using scenes::CountNear;
using scenes::Room;

// The room as PCL holds it: organised (16 x 360), NaN where nothing returned.
pcl::PointCloud<pcl::PointXYZI> RoomAsPcl() {
  const OrganisedCloud room = Room(-180, true);
  pcl::PointCloud<pcl::PointXYZI> cloud;
  cloud.width = static_cast<uint32_t>(room.columns);
  cloud.height = static_cast<uint32_t>(room.rows);
  cloud.is_dense = false;
  for (const Eigen::Vector3f& p : room.points) {
    pcl::PointXYZI q;
    q.x = p.x();
    q.y = p.y();
    q.z = p.z();
    q.intensity = 1.0f;
    cloud.push_back(q);
  }
  cloud.width = static_cast<uint32_t>(room.columns);  // push_back made it one row
  cloud.height = static_cast<uint32_t>(room.rows);
  return cloud;
}

void ExpectTheRoom(const CloudFile& file) {
  const auto planes = ExtractPlanes(file, true, PlaneExtractionParams());
  ASSERT_TRUE(planes.ok()) << planes.status().message();
  EXPECT_EQ(CountNear(*planes, Eigen::Vector3d::UnitZ(), 1.0), 1);
  EXPECT_EQ(CountNear(*planes, -Eigen::Vector3d::UnitX(), 4.0), 1);
}

TEST(CloudFilesTest, AnOrganisedPcdStaysOrganised) {
  testing::TempDir dir;
  for (const bool binary : {false, true}) {
    const std::string path = dir.File(binary ? "room-bin.pcd" : "room.pcd");
    ASSERT_EQ(pcl::io::savePCDFile(path, RoomAsPcl(), binary), 0);
    const auto file = ReadCloudFile(path);
    ASSERT_TRUE(file.ok()) << file.status().message();
    EXPECT_TRUE(file->organised());
    EXPECT_EQ(file->rows, 16);
    EXPECT_EQ(file->columns, 360);
    ExpectTheRoom(*file);
    // As the robot would pass its driver's cloud straight in.
    const auto planes = ExtractPlanes(ToOrganisedCloud(RoomAsPcl(), true), PlaneExtractionParams());
    ASSERT_TRUE(planes.ok());
    EXPECT_EQ(planes->size(), 2U);
  }
}

TEST(CloudFilesTest, PlyAndTextAreUnorganised) {
  testing::TempDir dir;
  pcl::PointCloud<pcl::PointXYZ> returns;
  std::string text = "# x y z\n\n";
  for (const Eigen::Vector3f& p : scenes::DenseRoom()) {
    returns.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    text +=
        std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  }
  const std::string ply = dir.File("room.PLY");  // extensions in any case
  ASSERT_EQ(pcl::io::savePLYFileBinary(ply, returns), 0);
  const std::string xyz = dir.File("room.xyz");
  std::ofstream(xyz) << text;
  for (const std::string& path : {ply, xyz}) {
    const auto file = ReadCloudFile(path);
    ASSERT_TRUE(file.ok()) << path << ": " << file.status().message();
    EXPECT_FALSE(file->organised());
    EXPECT_EQ(file->points.size(), returns.size());
    ExpectTheRoom(*file);
  }
  EXPECT_EQ(ToPoints(returns).size(), returns.size());

  // KITTI's Velodyne .bin: x y z reflectance, float32.
  std::vector<float> bin;
  for (const pcl::PointXYZ& p : returns) bin.insert(bin.end(), {p.x, p.y, p.z, 0.5f});
  const std::string velodyne = dir.File("000000.bin");
  std::ofstream(velodyne, std::ios::binary)
      .write(reinterpret_cast<const char*>(bin.data()),
             static_cast<std::streamsize>(bin.size() * sizeof(float)));
  const auto file = ReadCloudFile(velodyne);
  ASSERT_TRUE(file.ok()) << file.status().message();
  ASSERT_EQ(file->points.size(), returns.size());
  EXPECT_EQ(file->points[7], Eigen::Vector3f(returns[7].x, returns[7].y, returns[7].z));
  ExpectTheRoom(*file);
}

TEST(CloudFilesTest, ABadFileIsNamed) {
  testing::TempDir dir;
  const auto expect = [](const std::string& path, StatusCode code, const std::string& what) {
    const auto file = ReadCloudFile(path);
    ASSERT_FALSE(file.ok()) << path;
    EXPECT_EQ(file.status().code(), code);
    EXPECT_NE(file.status().message().find(what), std::string::npos) << file.status().message();
  };
  expect(dir.File("none.pcd"), StatusCode::kNotFound, "cannot open point cloud");
  std::ofstream(dir.File("scan.las")) << "x";
  expect(dir.File("scan.las"), StatusCode::kInvalidArgument, "unknown point cloud format 'las'");
  std::ofstream(dir.File("junk.pcd")) << "not a pcd\n";
  expect(dir.File("junk.pcd"), StatusCode::kInvalidArgument, "junk.pcd is not a readable PCD");
  // Files PCL's reader crashes on are refused before it reads them.
  const std::string header =
      "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1000\nHEIGHT 1\n"
      "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1000\n";
  std::ofstream(dir.File("short.pcd")) << header << "DATA binary\n" << std::string(100, 'x');
  expect(dir.File("short.pcd"), StatusCode::kInvalidArgument,
         "100 bytes of data for 1000 points of 12 bytes");
  std::ofstream(dir.File("packed.pcd")) << header << "DATA binary_compressed\n"
                                        << std::string(100, '\xff');
  expect(dir.File("packed.pcd"), StatusCode::kInvalidArgument, "compressed data's sizes");
  std::ofstream(dir.File("wide.pcd")) << "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 10\n"
                                         "HEIGHT 2\nPOINTS 10\nDATA ascii\n";
  expect(dir.File("wide.pcd"), StatusCode::kInvalidArgument, "WIDTH x HEIGHT is not POINTS");
  std::ofstream(dir.File("junk.ply")) << "ply\nformat nonsense\n";
  expect(dir.File("junk.ply"), StatusCode::kInvalidArgument, "junk.ply is not a readable PLY");
  std::ofstream(dir.File("short.bin")) << "0123456789";
  expect(dir.File("short.bin"), StatusCode::kInvalidArgument, "10 bytes, not a whole number");
  std::ofstream(dir.File("bad.xyz")) << "1 2 3\n4 5\n";
  expect(dir.File("bad.xyz"), StatusCode::kInvalidArgument, "bad.xyz:2: not an 'x y z' line");
  pcl::PointCloud<pcl::Normal> normals;  // a PCD without x y z
  normals.push_back(pcl::Normal(0, 0, 1));
  ASSERT_EQ(pcl::io::savePCDFileASCII(dir.File("normals.pcd"), normals), 0);
  expect(dir.File("normals.pcd"), StatusCode::kInvalidArgument, "has no 'x' field");
  std::ofstream(dir.File("empty.xyz")) << "";
  const auto empty = ReadCloudFile(dir.File("empty.xyz"));
  ASSERT_TRUE(empty.ok());
  EXPECT_TRUE(empty->points.empty());
}

// Every truncation of good PCD (ascii, binary, compressed) and PLY files is
// read or refused, never a crash: a robot's disk fills up mid-write.
TEST(CloudFilesTest, TruncatedFilesAreReadOrRefusedNeverACrash) {
  testing::TempDir dir;
  const pcl::PointCloud<pcl::PointXYZI> room = RoomAsPcl();
  pcl::PCDWriter writer;
  ASSERT_EQ(writer.writeASCII(dir.File("a.pcd"), room), 0);
  ASSERT_EQ(writer.writeBinary(dir.File("b.pcd"), room), 0);
  ASSERT_EQ(writer.writeBinaryCompressed(dir.File("c.pcd"), room), 0);
  pcl::PointCloud<pcl::PointXYZ> returns;
  for (const Eigen::Vector3f& p : scenes::DenseRoom())
    returns.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  ASSERT_EQ(pcl::io::savePLYFileBinary(dir.File("d.ply"), returns), 0);
  ASSERT_EQ(pcl::io::savePLYFileASCII(dir.File("e.ply"), returns), 0);
  size_t refused = 0, read = 0;
  for (const std::string name : {"a.pcd", "b.pcd", "c.pcd", "d.ply", "e.ply"}) {
    const std::string bytes = testing::ReadFileBytes(dir.File(name));
    ASSERT_FALSE(bytes.empty());
    const std::string cut = dir.File("cut" + name.substr(name.size() - 4));
    for (size_t length = 0; length < bytes.size(); length += 1 + bytes.size() / 23) {
      std::ofstream(cut, std::ios::binary | std::ios::trunc) << bytes.substr(0, length);
      const auto file = ReadCloudFile(cut);
      (file.ok() ? read : refused) += 1;
    }
  }
  EXPECT_GT(refused, 0U);
}

}  // namespace
}  // namespace mapd::robot
