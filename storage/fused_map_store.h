// The published fused map: one row per fused wall (line) and per fused
// non-vertical plane, as the fusion engines last published them.
// One intent of storage::Store (storage/store.h).
#ifndef MAPD_STORAGE_FUSED_MAP_STORE_H_
#define MAPD_STORAGE_FUSED_MAP_STORE_H_

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "common/status.h"
#include "geometry/segment2.h"

namespace mapd::storage {

// A row of the published fused map.
struct FusedRow {
  uint64_t id = 0;
  int kind = 1;  // 1 = line, 2 = plane (mapserver.v1.FeatureKind)
  geometry::Segment2 segment;
  double z_min_m = 0, z_max_m = 0;
  uint32_t support = 0;
  uint32_t member_count = 0;
  std::string robots;  // comma-separated robot names
};

// A row of the published fused non-vertical planes (fusion/plane_engine.h).
struct FusedPlaneRow {
  uint64_t id = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit, map frame
  double offset_m = 0;
  std::vector<Eigen::Vector3d> boundary;  // map frame, counter-clockwise about normal
  double area_m2 = 0;
  double z_min_m = 0, z_max_m = 0;
  uint32_t support = 0;
  uint32_t member_count = 0;
  std::string robots;  // comma-separated robot names
};

// Reads of the fused map. Any thread.
class FusedMapReader {
 public:
  virtual ~FusedMapReader() = default;
  virtual StatusOr<std::vector<FusedRow>> LoadFused() = 0;
  virtual StatusOr<std::vector<FusedPlaneRow>> LoadFusedPlanes() = 0;  // by id
};

// Writes to the fused map, in a WriteTransaction (storage/store.h).
class FusedMapWriter {
 public:
  virtual ~FusedMapWriter() = default;
  virtual Status UpsertFused(const FusedRow& row) = 0;
  virtual Status DeleteFused(uint64_t id) = 0;
  virtual Status UpsertFusedPlane(const FusedPlaneRow& row) = 0;
  virtual Status DeleteFusedPlane(uint64_t id) = 0;
  // A commit's changes at once (ids unique within each list): upserts, then
  // deletes. A backend may write each list in one statement (PostgreSQL
  // does); the default calls the methods above one row at a time.
  virtual Status WriteFused(const std::vector<FusedRow>& upserts,
                            const std::vector<uint64_t>& deletes);
  virtual Status WriteFusedPlanes(const std::vector<FusedPlaneRow>& upserts,
                                  const std::vector<uint64_t>& deletes);
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_FUSED_MAP_STORE_H_
