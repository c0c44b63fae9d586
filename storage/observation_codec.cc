#include "storage/observation_codec.h"

#include <cstdint>
#include <cstring>

namespace mapd::storage {
namespace {

constexpr uint32_t kVersion = 1;

void PutU32(uint32_t v, std::string* out) { out->append(reinterpret_cast<const char*>(&v), 4); }
void PutF64(double v, std::string* out) { out->append(reinterpret_cast<const char*>(&v), 8); }
void PutVec(const Eigen::Vector3d& v, std::string* out) {
  PutF64(v.x(), out);
  PutF64(v.y(), out);
  PutF64(v.z(), out);
}

// Reads fixed-size values from a bounded buffer; any overrun sets failed().
class Reader {
 public:
  explicit Reader(std::string_view data) : data_(data) {}
  uint32_t U32() { return Take<uint32_t>(); }
  double F64() { return Take<double>(); }
  Eigen::Vector3d Vec() {
    const double x = F64(), y = F64(), z = F64();
    return {x, y, z};
  }
  bool failed() const { return failed_; }
  size_t remaining() const { return data_.size() - pos_; }

 private:
  template <typename T>
  T Take() {
    T v{};
    if (remaining() < sizeof(T)) {
      failed_ = true;
      return v;
    }
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string_view data_;
  size_t pos_ = 0;
  bool failed_ = false;
};

}  // namespace

void EncodeFeatures(const geometry::SensorObservation& obs, std::string* out) {
  static_assert(sizeof(double) == 8, "IEEE doubles expected");
  PutU32(kVersion, out);
  PutU32(static_cast<uint32_t>(obs.lines.size()), out);
  for (const auto& l : obs.lines) {
    PutVec(l.a, out);
    PutVec(l.b, out);
  }
  PutU32(static_cast<uint32_t>(obs.planes.size()), out);
  for (const auto& p : obs.planes) {
    PutVec(p.normal, out);
    PutF64(p.offset, out);
    PutU32(static_cast<uint32_t>(p.boundary.size()), out);
    for (const auto& q : p.boundary) PutVec(q, out);
  }
}

Status DecodeFeatures(std::string_view payload, geometry::SensorObservation* obs) {
  Reader r(payload);
  const uint32_t version = r.U32();
  if (!r.failed() && version != kVersion) {
    return Status::Internal("observation payload has unknown version " + std::to_string(version));
  }
  const uint32_t n_lines = r.U32();
  // Each count is checked against the bytes left before anything is allocated.
  if (r.failed() || n_lines > r.remaining() / 48) {
    return Status::Internal("observation payload truncated in its lines");
  }
  obs->lines.resize(n_lines);
  for (auto& l : obs->lines) {
    l.a = r.Vec();
    l.b = r.Vec();
  }
  const uint32_t n_planes = r.U32();
  if (r.failed() || n_planes > r.remaining() / 36) {
    return Status::Internal("observation payload truncated in its planes");
  }
  obs->planes.resize(n_planes);
  for (auto& p : obs->planes) {
    p.normal = r.Vec();
    p.offset = r.F64();
    const uint32_t n = r.U32();
    if (r.failed() || n > r.remaining() / 24) {
      return Status::Internal("observation payload truncated in a plane boundary");
    }
    p.boundary.resize(n);
    for (auto& q : p.boundary) q = r.Vec();
  }
  if (r.failed() || r.remaining() != 0) {
    return Status::Internal("observation payload has the wrong length");
  }
  return Status::Ok();
}

}  // namespace mapd::storage
