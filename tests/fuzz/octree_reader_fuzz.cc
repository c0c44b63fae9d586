// libFuzzer target: the safe OctoMap reader on the bytes of an uploaded .bt/.ot
// file (UploadSubmap, mapctl render). ReadOctree validates with our own parser
// and hands only what passes to OctoMap's reader, so this drives both.
// Beyond crashes and sanitizer reports, a bug is: OctoMap refusing or misreading
// a tree that the validator passed (ReadOctree's Internal errors), or a small
// limit not being enforced.
#include <octomap/OcTree.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "voxel/octree_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace mapd::voxel;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);

  mapd::StatusOr<OctreeSummary> summary = ValidateOctree(bytes);
  mapd::StatusOr<OcTreePtr> tree = ReadOctree(bytes);
  if (summary.ok() != tree.ok()) std::abort();  // validator and OctoMap disagree
  if (tree.ok() && (*tree)->size() != summary->num_nodes) std::abort();
  if (!tree.ok() && tree.status().code() == mapd::StatusCode::kInternal) std::abort();

  // A tight limit: the node cap (64 KiB / 48 = 1365 nodes) is within the
  // fuzzer's reach, so the ResourceExhausted paths are explored too.
  OctreeReadLimits small;
  small.max_bytes = 64 * 1024;
  mapd::StatusOr<OctreeSummary> limited = ValidateOctree(bytes, small);
  if (limited.ok() && limited->num_nodes > small.max_bytes / kOctreeBytesPerNode) std::abort();
  return 0;
}
