// Hand-built .bt bytes for the octree reader's hostile-input tests (the voxel
// reader's own tests and the service's upload tests use the same files).
#ifndef MAPD_TESTS_VOXEL_SUPPORT_HOSTILE_BT_H_
#define MAPD_TESTS_VOXEL_SUPPORT_HOSTILE_BT_H_

#include <string>

namespace mapd::testing {

// A .bt header with the given `size` (node count) and `res` fields, as text.
inline std::string BtHeader(const std::string& size, const std::string& res) {
  return "# Octomap OcTree binary file\n# comment\nid OcTree\nsize " + size + "\nres " + res +
         "\ndata\n";
}

// A .bt chain: `records` inner nodes, each with child 0 inner, the deepest one
// with child 0 an occupied leaf. Leaf depth = records; nodes = records + 1.
// 17 levels is one more than OctoMap allows; 100,000 overflowed its recursive reader.
inline std::string BtChain(int records) {
  std::string bytes = BtHeader(std::to_string(records + 1), "0.1");
  for (int i = 0; i + 1 < records; ++i) bytes += std::string("\x03\x00", 2);
  bytes += std::string("\x02\x00", 2);
  return bytes;
}

}  // namespace mapd::testing

#endif  // MAPD_TESTS_VOXEL_SUPPORT_HOSTILE_BT_H_
