// Writes the generated part of the fuzz seed corpus: small OctoMap files made
// with OctoMap itself (tests/common/octomap_scenes) and valid
// ObservationBatch messages (tests/common/batches.h), serialized.
// Usage: fuzz_make_seeds DIR   (writes DIR/octree_reader/*, DIR/ingest_batch/*)
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "common/batches.h"
#include "common/octomap_scenes.h"

namespace {

bool WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) std::fprintf(stderr, "cannot write %s\n", path.c_str());
  return static_cast<bool>(out);
}

// A small room: few nodes, so that mutations stay cheap.
mapd::testing::RoomScene SmallRoom(bool with_boxes) {
  mapd::testing::RoomScene scene;
  scene.size_x_m = 2.0;
  scene.size_y_m = 1.6;
  scene.height_m = 1.0;
  scene.resolution_m = 0.2;
  scene.with_boxes = with_boxes;
  return scene;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_make_seeds DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  using mapd::testing::RoomSubmap;
  using mapd::testing::YawTranslation;
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d moved = YawTranslation(M_PI / 2, Eigen::Vector3d(0.4, -0.2, 0));
  bool ok = true;
  const std::string oct = dir + "/octree_reader/";
  ok &= WriteFile(oct + "room.bt", RoomSubmap(SmallRoom(false), 0.0, 2.0, identity));
  ok &= WriteFile(oct + "room.ot", RoomSubmap(SmallRoom(false), 0.0, 2.0, identity, true));
  ok &= WriteFile(oct + "room_boxes_half.bt", RoomSubmap(SmallRoom(true), 0.0, 1.0, moved));
  ok &= WriteFile(oct + "room_boxes_half.ot", RoomSubmap(SmallRoom(true), 1.0, 2.0, moved, true));
  ok &= WriteFile(oct + "empty.bt", mapd::testing::BtHeader("0", "0.1"));
  ok &= WriteFile(oct + "chain16.bt", mapd::testing::BtChain(16));

  const std::string ing = dir + "/ingest_batch/";
  std::mt19937_64 rng(7);
  ok &= WriteFile(ing + "room_lines.pb",
                  mapd::testing::RoomBatch("r1", "s1", 1, 3.0, 2.0, 0.3, &rng).SerializeAsString());
  mapserver::v1::ObservationBatch local =
      mapd::testing::RoomBatch("robot-2", "2024.a_b", 42, 5.0, 4.0, -1.2, &rng);
  local.set_session_frame(mapserver::v1::SESSION_FRAME_LOCAL);
  ok &= WriteFile(ing + "room_lines_local.pb", local.SerializeAsString());
  mapserver::v1::ObservationBatch planes =
      mapd::testing::RoomBatch("r3", "s1", 7, 1.0, 1.0, 0.0, &rng);
  planes.clear_lines();
  auto* p = planes.add_planes();  // the wall x = 2 m in the sensor frame, 2 m x 2.5 m
  mapd::testing::SetVec3(Eigen::Vector3d(-1, 0, 0), p->mutable_normal());
  p->set_offset(2.0);
  for (const Eigen::Vector3d& v : {Eigen::Vector3d(2, -1, 0), Eigen::Vector3d(2, 1, 0),
                                   Eigen::Vector3d(2, 1, 2.5), Eigen::Vector3d(2, -1, 2.5)}) {
    mapd::testing::SetVec3(v, p->add_boundary());
  }
  ok &= WriteFile(ing + "plane.pb", planes.SerializeAsString());
  return ok ? 0 : 1;
}
