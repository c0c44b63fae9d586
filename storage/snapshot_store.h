// Snapshots of the fusion state, so that a restart replays only what came
// after the newest one. One intent of storage::Store (storage/store.h).
#ifndef MAPD_STORAGE_SNAPSHOT_STORE_H_
#define MAPD_STORAGE_SNAPSHOT_STORE_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"

namespace mapd::storage {

// A stored snapshot of the fusion state (MapCore): it reflects every tied
// observation with id <= through_observation and every tie with tie_seq <=
// through_tie_seq.
struct FusionSnapshot {
  int64_t id = 0;
  int64_t created_ns = 0;
  uint64_t map_version = 0;
  int64_t through_observation = 0;
  int64_t through_tie_seq = 0;
  std::string params;  // the fusion parameters it was built with
  std::string state;   // FusionEngine::SaveState()
  // PlaneFusionEngine::SaveState(); has_plane_state is false for snapshots
  // taken before plane fusion (schema version 5), which are then not used.
  std::string plane_state;
  bool has_plane_state = false;
};

// A snapshot written in parts: its bytes (state, then plane_state) in `count`
// parts named by `key`, each stored in a transaction of its own
// (SnapshotWriter::InsertSnapshotPart), so that no commit holds the
// database for long; the snapshot exists once its row is stored
// (SnapshotWriter::InsertSnapshot with these parts).
struct SnapshotParts {
  int64_t key = 0;  // unique per snapshot
  int count = 0;    // 0: the bytes are in the row itself
};

// `snapshot`'s bytes cut into the parts InsertSnapshot expects: state, then
// plane_state, in slices of at most `part_bytes` (> 0); views into `snapshot`.
std::vector<std::string_view> SnapshotPartsOf(const FusionSnapshot& snapshot, size_t part_bytes);

// Reads of the snapshots. Any thread.
class SnapshotReader {
 public:
  virtual ~SnapshotReader() = default;
  // The newest snapshot (skip = 1: the one before it), its parts put back
  // together; NotFound if none, Internal if its parts are not all there.
  virtual StatusOr<FusionSnapshot> LatestSnapshot(int skip = 0) = 0;
};

// Writes of snapshots, in a WriteTransaction (storage/store.h).
class SnapshotWriter {
 public:
  virtual ~SnapshotWriter() = default;
  // Stores a snapshot and deletes the rows of all but the `keep` newest (their
  // parts stay until DeleteUnusedSnapshotParts). With parts.count > 0, the
  // bytes are the parts stored before under parts.key, and only the sizes of
  // state and plane_state are taken from `snapshot`.
  virtual Status InsertSnapshot(const FusionSnapshot& snapshot, int keep,
                                SnapshotParts parts = {}) = 0;
  // Part `index` (0, 1, ...) of the snapshot that will name `key`.
  virtual Status InsertSnapshotPart(int64_t key, int index, std::string_view bytes) = 0;
  // Deletes up to `limit` parts that no stored snapshot names (a pruned
  // snapshot's, or those of one a stop or crash interrupted); returns how many.
  // Not while a snapshot's parts are being written: they are not named yet.
  virtual StatusOr<int> DeleteUnusedSnapshotParts(int limit) = 0;
  // Raw retention, which snapshots make possible: deletes up to `limit` of
  // the oldest observations received before `received_before_ns` that every
  // stored snapshot reflects (never one of a session not tied, or tied after
  // a snapshot, and never the newest observation, so ids keep growing), then
  // returns the freed space where the backend can. Returns how many.
  virtual StatusOr<uint64_t> DropRawObservations(int64_t received_before_ns, int limit) = 0;
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_SNAPSHOT_STORE_H_
