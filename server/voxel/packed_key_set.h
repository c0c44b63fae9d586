// A set of packed voxel keys (48-bit integers, voxel_grid.cc) in one flat
// table: open addressing with linear probing, at most half full, plus the
// keys in the order they were first inserted (for iteration).
//
// Why not std::unordered_set: a 150k-voxel submap carries 0.1-0.7M free
// cubes (the benchmark's indoor and campus crops), and a node per key (a
// malloc each, a pointer chase per lookup and per step of iteration) made
// building and walking a VoxelGrid a tenth of a merge (docs/voxel-merge.md).
// Iteration in insertion order also makes the order of
// VoxelGrid::ForEachFreeCube the map's own (its leaves' order), not the hash
// table's.
//
// Thread compatible: const methods may be called concurrently.
#ifndef MAPD_VOXEL_PACKED_KEY_SET_H_
#define MAPD_VOXEL_PACKED_KEY_SET_H_

#include <cstddef>
#include <cstdint>
#include <vector>

namespace mapd::voxel {

class PackedKeySet {
 public:
  // Room for `count` keys without growing.
  void reserve(std::size_t count) {
    if (2 * count > slots_.size()) Rehash(2 * count);
    keys_.reserve(count);
  }
  // Inserts `key` (REQUIRES: key != kEmpty); false if it was there.
  bool insert(std::uint64_t key) {
    if (2 * (keys_.size() + 1) > slots_.size()) Rehash(2 * (keys_.size() + 1));
    const std::size_t slot = SlotOf(key);
    if (slots_[slot] == key) return false;
    slots_[slot] = key;
    keys_.push_back(key);
    return true;
  }
  bool contains(std::uint64_t key) const { return !slots_.empty() && slots_[SlotOf(key)] == key; }
  void clear() {
    slots_.clear();
    keys_.clear();
  }
  std::size_t size() const { return keys_.size(); }
  bool empty() const { return keys_.empty(); }
  // In the order of first insertion.
  const std::vector<std::uint64_t>& keys() const { return keys_; }
  // Heap bytes held.
  std::size_t MemoryBytes() const {
    return (slots_.capacity() + keys_.capacity()) * sizeof(std::uint64_t);
  }

  // No packed key is all ones (they use 48 bits).
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};

 private:
  // The slot holding `key`, or the empty slot where it would go.
  // REQUIRES: !slots_.empty() and at least one empty slot.
  std::size_t SlotOf(std::uint64_t key) const {
    const std::size_t mask = slots_.size() - 1;
    // Fibonacci hashing: the packed axes sit in fixed bit fields, so the
    // multiply spreads all of them into the high bits taken here.
    std::size_t i = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> shift_) & mask;
    while (slots_[i] != key && slots_[i] != kEmpty) i = (i + 1) & mask;
    return i;
  }
  // A table of at least `min_slots` (a power of two, >= 16) holding keys_.
  void Rehash(std::size_t min_slots) {
    std::size_t slots = 16;
    int bits = 4;
    while (slots < min_slots) slots *= 2, ++bits;
    slots_.assign(slots, kEmpty);
    shift_ = 64 - bits;
    for (std::uint64_t key : keys_) slots_[SlotOf(key)] = key;
  }

  std::vector<std::uint64_t> slots_;
  std::vector<std::uint64_t> keys_;
  int shift_ = 60;
};

}  // namespace mapd::voxel

#endif  // MAPD_VOXEL_PACKED_KEY_SET_H_
