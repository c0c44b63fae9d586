// Heap bytes of standard containers, for the prepared submaps' memory
// estimate (merge.h PreparedSubmap::MemoryBytes). Approximate for node-based
// containers: one node per element (element, next pointer, cached hash,
// rounded to malloc's 16-byte chunks plus its 8-byte header) and the bucket
// array.
#ifndef MAPD_VOXEL_MEMORY_BYTES_H_
#define MAPD_VOXEL_MEMORY_BYTES_H_

#include <cstddef>
#include <unordered_map>
#include <vector>

namespace mapd::voxel {

template <typename T>
std::size_t MemoryBytes(const std::vector<T>& v) {
  return v.capacity() * sizeof(T);
}

template <typename K, typename V>
std::size_t MemoryBytes(const std::unordered_map<K, V>& m) {
  constexpr std::size_t kNode =
      (sizeof(typename std::unordered_map<K, V>::value_type) + 16 + 8 + 15) / 16 * 16;
  return m.size() * kNode + m.bucket_count() * sizeof(void*);
}

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_MEMORY_BYTES_H_
