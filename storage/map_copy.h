// Copies one map from one Store to another, whatever their backends: a
// SQLite file into PostgreSQL, or back (`mapd migrate`, docs/scale-out.md).
//
// What is kept: every observation with its id, (robot, session, seq), stamps
// and features; the session frames and every tie at its place in the commit
// order (same tied_through_observation and tie_seq), so that the target
// fuses to the same map; the published fused map; submaps with their bytes,
// merges, placements and the global map; the audit log; tokens on request.
// What changes: robot, session, submap and merge ids are the target's own
// (submap and merge ids are reported old -> new); snapshots are not copied,
// since the fusion state in them names robots by id: the first mapd to open
// the copy rebuilds it from the observations (as after a change of fusion
// settings) and takes a snapshot then.
//
// A map whose raw observations were thinned by retention cannot be copied:
// its fused map depends on a snapshot, which cannot move. CopyMap finds the
// gap in the observation ids and fails FailedPrecondition.
#ifndef MAPD_STORAGE_MAP_COPY_H_
#define MAPD_STORAGE_MAP_COPY_H_

#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "common/status.h"
#include "storage/store.h"

namespace mapd::storage {

struct MapCopyReport {
  uint64_t robots = 0;
  uint64_t sessions = 0;
  uint64_t ties = 0;  // tying transactions replayed
  uint64_t observations = 0;
  uint64_t fused_lines = 0;
  uint64_t fused_planes = 0;
  uint64_t submaps = 0;  // merged maps included
  uint64_t merges = 0;
  uint64_t placements = 0;
  bool global_map = false;
  uint64_t audit_rows = 0;
  uint64_t tokens = 0;
  // Inputs of refused merges whose submap was deleted since: recorded as 0.
  uint64_t unknown_merge_inputs = 0;
  std::map<int64_t, int64_t> submap_ids;  // source id -> target id
  std::map<int64_t, int64_t> merge_ids;   // source id -> target id
};

struct MapCopyOptions {
  // Observations per write transaction of the target.
  int observations_per_commit = 512;
  // Tokens are the server's, not a map's: copied only when asked. A token
  // that acts on every map is then scoped to `scope_tokens_to` when it is
  // not empty (a site's robots keep writing their site, not every map).
  bool copy_tokens = false;
  std::string scope_tokens_to;
  // Runs after every commit of the target, with what is copied so far; an
  // error stops the copy (mapd migrate renews its lease here).
  std::function<Status(const MapCopyReport&)> after_commit;
};

// Copies `from` into `to`, which must hold no map data (FailedPrecondition
// otherwise). Writes many transactions: on failure `to` holds part of the
// map, and the caller discards it. The source must not change meanwhile (no
// mapd serving it).
StatusOr<MapCopyReport> CopyMap(Store& from, Store& to, const MapCopyOptions& options = {});

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_MAP_COPY_H_
