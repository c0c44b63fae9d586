// Rendezvous (highest-random-weight) hashing: which of the live instances a
// map belongs to. Every instance computes the same answer from the same
// list, with no coordination; when an instance leaves, only its maps move,
// and each to a different survivor, so a failure spreads its load.
#ifndef MAPD_SERVICE_RENDEZVOUS_H_
#define MAPD_SERVICE_RENDEZVOUS_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mapd::service {

// A 64-bit weight of (map, instance), the same on every host and build
// (FNV-1a then the splitmix64 finaliser; std::hash promises neither).
inline uint64_t RendezvousWeight(std::string_view map_id, std::string_view instance) {
  uint64_t h = 14695981039346656037ull;
  auto mix = [&h](std::string_view s) {
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
  };
  mix(map_id);
  mix(std::string_view("\0", 1));  // ("ab","c") and ("a","bc") differ
  mix(instance);
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  return h ^ (h >> 31);
}

// The instance of `instances` with the highest weight for `map_id` (ties: the
// smaller name); empty when there is none.
inline std::string RendezvousPick(std::string_view map_id,
                                  const std::vector<std::string>& instances) {
  std::string best;
  uint64_t best_weight = 0;
  for (const std::string& i : instances) {
    const uint64_t w = RendezvousWeight(map_id, i);
    if (best.empty() || w > best_weight || (w == best_weight && i < best)) {
      best = i;
      best_weight = w;
    }
  }
  return best;
}

}  // namespace mapd::service

#endif  // MAPD_SERVICE_RENDEZVOUS_H_
