// The byte codec of the engines' snapshots (engine_state.cc,
// plane_engine_state.cc): little-endian fixed-width values, doubles as their
// IEEE bits (a restored engine continues bit for bit), length-prefixed
// strings and id lists, and the FNV-1a checksum that closes a snapshot.
// Header-only: small, and private to the fusion library.
#ifndef MAPD_FUSION_STATE_CODEC_H_
#define MAPD_FUSION_STATE_CODEC_H_

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"

namespace mapd::fusion {

// Both engines keep clusters as a union-find forest joined by size, so a tree
// is at most log2(nodes) deep; a snapshot whose forest is deeper is corrupt.
inline constexpr int kMaxForestDepth = 64;

inline uint64_t Fnv1a(std::string_view bytes) {
  uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

// The checksum of newer snapshots: four lanes over 8-byte words, each round
// multiply, rotate, multiply (the round of xxHash64, with its primes), the
// lanes folded and the tail bytes and length mixed in at the end. Every bit of
// a word reaches every bit of its lane. Byte-wise FNV-1a alone took 27 ms
// over a 24 MB fusion state; encoding it took 52 ms with FNV-1a and 16 ms
// with this (tests/bench/snapshot_bench).
inline uint64_t WordChecksum(std::string_view bytes) {
  constexpr uint64_t kP1 = 0x9E3779B185EBCA87ULL;
  constexpr uint64_t kP2 = 0xC2B2AE3D27D4EB4FULL;
  const auto rotl = [](uint64_t x, int r) { return (x << r) | (x >> (64 - r)); };
  const auto round = [&](uint64_t acc, uint64_t word) { return rotl(acc + word * kP2, 31) * kP1; };
  uint64_t lane[4] = {kP1 + kP2, kP2, 0, 0 - kP1};
  const char* p = bytes.data();
  size_t n = bytes.size();
  for (; n >= 32; n -= 32, p += 32) {
    for (int k = 0; k < 4; ++k) {
      uint64_t word;
      std::memcpy(&word, p + 8 * k, 8);
      lane[k] = round(lane[k], word);
    }
  }
  uint64_t h = rotl(lane[0], 1) + rotl(lane[1], 7) + rotl(lane[2], 12) + rotl(lane[3], 18);
  for (int k = 0; k < 4; ++k) h = (h ^ round(0, lane[k])) * kP1 + 0x85EBCA77C2B2AE63ULL;
  h ^= bytes.size();
  for (; n >= 8; n -= 8, p += 8) {
    uint64_t word;
    std::memcpy(&word, p, 8);
    h = rotl(h ^ round(0, word), 27) * kP1 + 0x85EBCA77C2B2AE63ULL;
  }
  for (; n > 0; --n, ++p)
    h = rotl(h ^ (static_cast<unsigned char>(*p) * 0x27D4EB2F165667C5ULL), 11) * kP1;
  h ^= h >> 33;
  h *= kP2;
  h ^= h >> 29;
  return h;
}

// How a snapshot format closes (OpenSnapshot).
enum class SnapshotChecksum { kFnv1a, kWords };

inline uint64_t ChecksumOf(std::string_view bytes, SnapshotChecksum kind) {
  return kind == SnapshotChecksum::kWords ? WordChecksum(bytes) : Fnv1a(bytes);
}

class StateWriter {
 public:
  explicit StateWriter(std::string* out) : out_(out) {}
  template <typename T>
  void Raw(const T& v) {
    out_->append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void U8(uint8_t v) { Raw(v); }
  void U32(uint32_t v) { Raw(v); }
  void U64(uint64_t v) { Raw(v); }
  void F64(double v) { Raw(v); }
  void Str(std::string_view s) {
    U64(s.size());
    out_->append(s);
  }
  void Ids(const std::vector<uint64_t>& ids) {
    U64(ids.size());
    for (uint64_t id : ids) U64(id);
  }

 private:
  std::string* out_;
};

// Reads what StateWriter wrote. A read past the end, or a count the rest of
// the bytes cannot hold, clears ok() and yields zeros from then on: callers
// check ok() once, after reading.
class StateReader {
 public:
  explicit StateReader(std::string_view in) : in_(in) {}
  bool ok() const { return ok_; }
  bool at_end() const { return pos_ == in_.size(); }
  template <typename T>
  T Raw() {
    T v{};
    if (!ok_ || in_.size() - pos_ < sizeof(T)) {
      ok_ = false;
      return v;
    }
    std::memcpy(&v, in_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  uint8_t U8() { return Raw<uint8_t>(); }
  uint32_t U32() { return Raw<uint32_t>(); }
  uint64_t U64() { return Raw<uint64_t>(); }
  double F64() { return Raw<double>(); }
  // A count of items of at least `item_bytes` each that the rest can hold.
  uint64_t Count(size_t item_bytes) {
    const uint64_t n = U64();
    if (!ok_ || n > (in_.size() - pos_) / item_bytes) ok_ = false;
    return ok_ ? n : 0;
  }
  std::string Str() {
    const uint64_t n = Count(1);
    if (!ok_) return {};
    std::string s(in_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  std::vector<uint64_t> Ids() {
    std::vector<uint64_t> ids(Count(8));
    for (uint64_t& id : ids) id = U64();
    return ids;
  }
  std::string_view rest() const { return in_.substr(pos_); }

 private:
  std::string_view in_;
  size_t pos_ = 0;
  bool ok_ = true;
};

// A format version an engine reads, and the checksum that closes it.
struct SnapshotFormat {
  uint32_t version;
  SnapshotChecksum checksum;
};

// Every snapshot is framed alike: magic, format version, the parameters key
// (a snapshot is valid only for the parameters it was taken with), the
// engine's payload, then the checksum of all before it (the format says
// which). Checks the frame against the formats the engine reads and returns
// the payload. `params_keys`: the keys whose snapshots the engine can
// continue from (its own first). `what` names the snapshot in errors
// ("fusion snapshot"): InvalidArgument when corrupt, FailedPrecondition when
// taken with other parameters.
inline StatusOr<std::string_view> OpenSnapshot(std::string_view state, std::string_view magic,
                                               std::initializer_list<SnapshotFormat> formats,
                                               const std::vector<std::string>& params_keys,
                                               const std::string& what) {
  const auto corrupt = [&what](const std::string& why) {
    return Status::InvalidArgument(what + " is corrupt: " + why);
  };
  if (state.size() < magic.size() + 12 || state.substr(0, magic.size()) != magic) {
    return corrupt("not a " + what);
  }
  const std::string_view body = state.substr(0, state.size() - 8);
  StateReader r(body.substr(magic.size()));
  const uint32_t version = r.U32();
  const SnapshotFormat* format = nullptr;
  for (const SnapshotFormat& f : formats) {
    if (f.version == version) format = &f;
  }
  // (A newer mapd's snapshot: this one replays the observations instead.)
  if (format == nullptr) return corrupt("unknown format version " + std::to_string(version));
  uint64_t stored_hash;
  std::memcpy(&stored_hash, state.data() + body.size(), 8);
  if (ChecksumOf(body, format->checksum) != stored_hash) return corrupt("checksum mismatch");
  const std::string key = r.Str();
  if (!r.ok()) return corrupt("truncated header");
  if (std::find(params_keys.begin(), params_keys.end(), key) == params_keys.end()) {
    return Status::FailedPrecondition(what + " was taken with other parameters (" + key + ")");
  }
  return r.rest();
}

}  // namespace mapd::fusion

#endif  // MAPD_FUSION_STATE_CODEC_H_
