#include "storage/sqlite/schema.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "storage/sqlite/sqlite.h"

namespace mapd::storage {
namespace {

// Migration i takes the schema from version i to i + 1. Append only: never edit
// a migration that has shipped.
const std::vector<const char*>& Migrations() {
  static const std::vector<const char*> kMigrations = {
      // 0 -> 1: the initial schema.
      R"sql(
      CREATE TABLE robots (
        id            INTEGER PRIMARY KEY,
        name          TEXT NOT NULL UNIQUE,
        first_seen_ns INTEGER NOT NULL,
        last_seen_ns  INTEGER NOT NULL,
        batches       INTEGER NOT NULL DEFAULT 0,
        features      INTEGER NOT NULL DEFAULT 0
      );
      -- One frame per robot session. T_map_frame is NULL until the frame is tied to the map.
      CREATE TABLE sessions (
        id         INTEGER PRIMARY KEY,
        robot_id   INTEGER NOT NULL REFERENCES robots(id),
        name       TEXT NOT NULL,
        created_ns INTEGER NOT NULL,
        frame_kind INTEGER NOT NULL,   -- 1 = poses in the map frame, 2 = own frame
        tied       INTEGER NOT NULL,   -- 1 when T_map_frame is known
        qw REAL, qx REAL, qy REAL, qz REAL, tx REAL, ty REAL, tz REAL,
        UNIQUE (robot_id, name)
      );
      -- Raw observations, never discarded. payload = the batch's lines and planes
      -- in the sensor frame (storage/observation_codec.h), so the fused map can
      -- always be recomputed, with other parameters if need be.
      CREATE TABLE observations (
        id          INTEGER PRIMARY KEY,
        session_id  INTEGER NOT NULL REFERENCES sessions(id),
        seq         INTEGER NOT NULL,
        stamp_ns    INTEGER NOT NULL,
        received_ns INTEGER NOT NULL,
        qw REAL NOT NULL, qx REAL NOT NULL, qy REAL NOT NULL, qz REAL NOT NULL,
        tx REAL NOT NULL, ty REAL NOT NULL, tz REAL NOT NULL,
        line_count  INTEGER NOT NULL,
        plane_count INTEGER NOT NULL,
        payload     BLOB NOT NULL,
        UNIQUE (session_id, seq)
      );
      -- The published fused map (derived: recomputable from observations).
      -- Membership: a raw feature's id is (observation id << 12 | index in batch);
      -- a cluster's id is its smallest member's id.
      CREATE TABLE fused_features (
        id           INTEGER PRIMARY KEY,
        kind         INTEGER NOT NULL,
        ax REAL NOT NULL, ay REAL NOT NULL, bx REAL NOT NULL, by REAL NOT NULL,
        z_min REAL NOT NULL, z_max REAL NOT NULL,
        support      INTEGER NOT NULL,
        member_count INTEGER NOT NULL,
        robots       TEXT NOT NULL,
        updated_ns   INTEGER NOT NULL
      );
      CREATE TABLE submaps (
        id          INTEGER PRIMARY KEY,
        robot_id    INTEGER NOT NULL REFERENCES robots(id),
        session_id  INTEGER REFERENCES sessions(id),
        name        TEXT NOT NULL,
        format      INTEGER NOT NULL,
        resolution  REAL NOT NULL,
        occupied    INTEGER NOT NULL,
        free        INTEGER NOT NULL,
        min_x REAL, min_y REAL, min_z REAL, max_x REAL, max_y REAL, max_z REAL,
        created_ns  INTEGER NOT NULL,
        data        BLOB NOT NULL,
        UNIQUE (robot_id, name)
      );
      CREATE TABLE merges (
        id               INTEGER PRIMARY KEY,
        created_ns       INTEGER NOT NULL,
        status           TEXT NOT NULL,   -- accepted / refused
        reason           TEXT NOT NULL,
        merged_submap_id INTEGER REFERENCES submaps(id)
      );
      CREATE TABLE merge_inputs (
        merge_id        INTEGER NOT NULL REFERENCES merges(id),
        submap_id       INTEGER NOT NULL,
        qw REAL, qx REAL, qy REAL, qz REAL, tx REAL, ty REAL, tz REAL,
        matched_corners INTEGER, residual_m REAL, overlap_score REAL,
        PRIMARY KEY (merge_id, submap_id)
      );
      )sql",
      // 1 -> 2: restarts from a snapshot of the fusion state (docs/operations.md).
      // A tie records where in the commit order it happened, so that a replay
      // fuses in the order the live server did: tied_through_observation = the
      // newest observation id committed before the tie, tie_seq = 1, 2, ...
      // per tying transaction (0: tied from the start, frame kind MAP).
      R"sql(
      ALTER TABLE sessions ADD COLUMN tied_through_observation INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE sessions ADD COLUMN tie_seq INTEGER NOT NULL DEFAULT 0;
      -- The fusion engine's state (derived: recomputable from observations while
      -- they are kept). It reflects every tied observation with id <=
      -- through_observation and every tie with tie_seq <= through_tie_seq.
      CREATE TABLE fusion_snapshots (
        id                  INTEGER PRIMARY KEY,
        created_ns          INTEGER NOT NULL,
        map_version         INTEGER NOT NULL,
        through_observation INTEGER NOT NULL,
        through_tie_seq     INTEGER NOT NULL,
        params              TEXT NOT NULL,   -- the fusion parameters it was built with
        state               BLOB NOT NULL
      );
      )sql",
      // 2 -> 3: identities and the audit log (docs/security.md). A token's
      // secret is never stored: only SHA-256 of it. Rows are never deleted
      // (a revoked token keeps its row), so "a token was ever created" is a
      // fact that cannot be undone by a revocation.
      R"sql(
      CREATE TABLE tokens (
        id            INTEGER PRIMARY KEY,
        name          TEXT NOT NULL UNIQUE,
        role          TEXT NOT NULL,              -- reader / robot / operator / admin
        robot_id      TEXT NOT NULL DEFAULT '',   -- the robot a robot token writes for
        secret_sha256 BLOB NOT NULL,
        created_ns    INTEGER NOT NULL,
        created_by    TEXT NOT NULL,
        revoked_ns    INTEGER                     -- NULL while valid
      );
      CREATE TABLE audit_log (
        id      INTEGER PRIMARY KEY,
        time_ns INTEGER NOT NULL,
        who     TEXT NOT NULL,   -- token name or certificate CN
        role    TEXT NOT NULL,
        action  TEXT NOT NULL,   -- e.g. UploadSubmap, MergeSubmaps, CreateToken
        target  TEXT NOT NULL,
        result  TEXT NOT NULL    -- ok, denied: ..., or the error
      );
      )sql",
      // 3 -> 4: a scratch table for SqliteStore::ProbeWrite (empty between probes).
      R"sql(
      CREATE TABLE write_probe (data BLOB NOT NULL);
      )sql",
      // 4 -> 5: fused non-vertical planes (floors, ceilings, ramps;
      // server/fusion/plane_engine.h), derived like fused_features. The plane
      // engine's snapshot rides with the line engine's: a snapshot without
      // plane_state (taken before this version) is not used, and the first
      // start after the upgrade replays the stored observations once.
      R"sql(
      CREATE TABLE fused_planes (
        id           INTEGER PRIMARY KEY,   -- smallest member feature id
        nx REAL NOT NULL, ny REAL NOT NULL, nz REAL NOT NULL,  -- unit normal, map frame
        offset       REAL NOT NULL,         -- n.x + offset = 0, metres
        boundary     BLOB NOT NULL,         -- x, y, z doubles (little-endian), counter-clockwise about n
        area         REAL NOT NULL,         -- m^2
        z_min REAL NOT NULL, z_max REAL NOT NULL,
        support      INTEGER NOT NULL,
        member_count INTEGER NOT NULL,
        robots       TEXT NOT NULL,
        updated_ns   INTEGER NOT NULL
      );
      ALTER TABLE fusion_snapshots ADD COLUMN plane_state BLOB;
      )sql",
      // 5 -> 6: merge review (docs/operations.md, "Merges: records and review"). merges.status
      // gains 'proposed' (accepted by the gates, waiting for an operator) and
      // 'rejected' (by an operator); who asked, who decided and when. Older
      // merges keep 'accepted' / 'refused'; an accepted one counts as decided
      // when it was made, so the global map stays the one it was.
      R"sql(
      ALTER TABLE merges ADD COLUMN requested_by TEXT NOT NULL DEFAULT '';
      ALTER TABLE merges ADD COLUMN decided_by TEXT NOT NULL DEFAULT '';
      ALTER TABLE merges ADD COLUMN decided_ns INTEGER NOT NULL DEFAULT 0;
      UPDATE merges SET decided_ns = created_ns WHERE status = 'accepted';
      )sql",
      // 6 -> 7: the matched corner pairs behind merge_inputs.matched_corners, for
      // operators reviewing a merge: 6 doubles per pair (in_submap x, y, z, then
      // in_reference x, y, z; machine byte order, little-endian). NULL in
      // merges recorded before this version: they read as no pairs.
      R"sql(
      ALTER TABLE merge_inputs ADD COLUMN matched_points BLOB;
      )sql",
      // 7 -> 8: the rest of the placing edge's gate figures (MergeInputRecord),
      // for operators reviewing a merge. NULL in merges recorded before this
      // version: they read as not measured (-1) and no source.
      R"sql(
      ALTER TABLE merge_inputs ADD COLUMN source TEXT;
      ALTER TABLE merge_inputs ADD COLUMN support_fraction REAL;
      ALTER TABLE merge_inputs ADD COLUMN shared_free_ratio REAL;
      ALTER TABLE merge_inputs ADD COLUMN restart_spread_voxels REAL;
      ALTER TABLE merge_inputs ADD COLUMN second_residual_m REAL;
      )sql",
      // 8 -> 9: snapshots in parts. A fusion state of tens of MB written in
      // one transaction held the database for 350 ms, and every robot's
      // acknowledgement waited (issue 46). Its bytes (state, then plane_state)
      // now go in parts of about 1 MiB, each committed on its own between other
      // writes; the fusion_snapshots row, written last, names them (parts > 0,
      // state empty, plane_state an empty blob if there is one). Parts that no
      // row names (a stop or crash mid-write, a pruned snapshot) are deleted
      // after the next snapshot.
      R"sql(
      ALTER TABLE fusion_snapshots ADD COLUMN parts INTEGER NOT NULL DEFAULT 0;
      ALTER TABLE fusion_snapshots ADD COLUMN parts_key INTEGER;
      ALTER TABLE fusion_snapshots ADD COLUMN state_bytes INTEGER;
      CREATE TABLE fusion_snapshot_parts (
        id        INTEGER PRIMARY KEY,
        parts_key INTEGER NOT NULL,
        part      INTEGER NOT NULL,
        bytes     BLOB NOT NULL,
        UNIQUE (parts_key, part)
      );
      )sql",
      // 9 -> 10: audit rows name the caller's address and how it proved who
      // it is ("token", "certificate", "none" in the open mode, "database
      // file" for `mapd token`); rows from before read as ''.
      R"sql(
      ALTER TABLE audit_log ADD COLUMN peer TEXT NOT NULL DEFAULT '';
      ALTER TABLE audit_log ADD COLUMN credential TEXT NOT NULL DEFAULT '';
      )sql",
      // 10 -> 11: the global map as the union of every placed submap (issue
      // 42; docs/operations.md, "The global map"). submap_placements: where an
      // accepted merge put each of its inputs in the map frame (the first
      // placement stays, like a session tie). global_map: one row, the union
      // as built last; members = "submap_id qw qx qy qz tx ty tz" lines in the
      // order they were fused. Older databases start without one: mapd builds
      // it from their accepted merges' inputs at start.
      R"sql(
      CREATE TABLE submap_placements (
        submap_id INTEGER PRIMARY KEY,
        merge_id  INTEGER NOT NULL,
        qw REAL NOT NULL, qx REAL NOT NULL, qy REAL NOT NULL, qz REAL NOT NULL,
        tx REAL NOT NULL, ty REAL NOT NULL, tz REAL NOT NULL
      );
      CREATE TABLE global_map (
        id          INTEGER PRIMARY KEY CHECK (id = 1),
        version     INTEGER NOT NULL,
        built_ns    INTEGER NOT NULL,
        resolution  REAL NOT NULL,
        occupied    INTEGER NOT NULL,
        free        INTEGER NOT NULL,
        members     TEXT NOT NULL,
        data        BLOB NOT NULL
      );
      )sql",
      // 11 -> 12: a token may be scoped to maps (issue 41): comma-separated
      // map ids, '' = every map (as every token before this version).
      R"sql(
      ALTER TABLE tokens ADD COLUMN maps TEXT NOT NULL DEFAULT '';
      )sql",
  };
  return kMigrations;
}

StatusOr<int> ReadVersion(sqlite3* db) {
  MAPD_RETURN_IF_ERROR(
      Exec(db, "CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)"));
  StatusOr<Statement> q = Statement::Prepare(db, "SELECT max(version) FROM schema_version");
  if (!q.ok()) return q.status();
  StatusOr<bool> row = q->Step();
  if (!row.ok()) return row.status();
  return (*row && !q->ColumnIsNull(0)) ? static_cast<int>(q->ColumnInt(0)) : 0;
}

}  // namespace

int CurrentSchemaVersion() { return static_cast<int>(Migrations().size()); }

Status ClaimDatabase(sqlite3* db, const std::string& path) {
  // SQLite opens a file it cannot write read-only without a word.
  if (sqlite3_db_readonly(db, "main") == 1) {
    return Status::FailedPrecondition(
        "database '" + path +
        "' is read-only (file or directory permissions, or a read-only mount); "
        "mapd must be able to write it");
  }
  StatusOr<Statement> id_query = Statement::Prepare(db, "PRAGMA application_id");
  if (!id_query.ok()) return id_query.status();
  StatusOr<bool> id_row = id_query->Step();
  if (!id_row.ok()) {
    return Status::FailedPrecondition("cannot read '" + path +
                                      "' as an SQLite database: " + id_row.status().message());
  }
  const int32_t id = *id_row ? static_cast<int32_t>(id_query->ColumnInt(0)) : 0;
  id_query = Status::Ok();  // finalize
  if (id != 0 && id != kApplicationId) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%08x", static_cast<uint32_t>(id));
    return Status::FailedPrecondition("'" + path +
                                      "' is not a mapd database (its application_id is " + hex +
                                      ", another application's); give mapd a --db of its own");
  }
  if (id == 0) {
    StatusOr<Statement> tables =
        Statement::Prepare(db,
                           "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT LIKE "
                           "'sqlite_%' ORDER BY name");
    if (!tables.ok()) return tables.status();
    std::vector<std::string> names;
    bool mapd_tables = false;
    for (;;) {
      StatusOr<bool> row = tables->Step();
      if (!row.ok()) return row.status();
      if (!*row) break;
      names.push_back(tables->ColumnText(0));
      mapd_tables |= names.back() == "observations";
    }
    const bool earlier_mapd =
        mapd_tables && std::find(names.begin(), names.end(), "schema_version") != names.end();
    if (!names.empty() && !earlier_mapd) {
      std::string list;
      for (size_t i = 0; i < names.size() && i < 5; ++i) list += (i ? ", " : "") + names[i];
      if (names.size() > 5) list += ", ...";
      return Status::FailedPrecondition(
          "'" + path + "' holds tables of another application (" + list +
          ") and is not a mapd database; give mapd a --db of its own");
    }
  }
  // A new database gives freed pages back to the file system (raw retention,
  // SqliteWriteTransaction::DropRawObservations); on an existing one this is a
  // no-op. Before the first write below, or it is too late.
  MAPD_RETURN_IF_ERROR(Exec(db, "PRAGMA auto_vacuum=INCREMENTAL"));
  // Written every start: the first write, so a database mapd cannot write is
  // refused now rather than answered SERVING while every commit fails.
  Status stamp = Exec(db, "PRAGMA application_id = " + std::to_string(kApplicationId));
  if (!stamp.ok()) {
    const int code = sqlite3_extended_errcode(db) & 0xff;
    if (code == SQLITE_READONLY || code == SQLITE_CANTOPEN || code == SQLITE_PERM) {
      return Status::FailedPrecondition(
          "database '" + path +
          "' is read-only (file or directory permissions, or a read-only "
          "mount); mapd must be able to write it: " +
          stamp.message());
    }
    return Status(stamp.code(), "cannot write database '" + path + "': " + stamp.message());
  }
  return Status::Ok();
}

Status Migrate(sqlite3* db) {
  StatusOr<int> version = ReadVersion(db);
  if (!version.ok()) return version.status();
  if (*version > CurrentSchemaVersion()) {
    return Status::FailedPrecondition(
        "database schema version " + std::to_string(*version) + " is newer than this mapd (" +
        std::to_string(CurrentSchemaVersion()) + "); upgrade mapd or use another --db");
  }
  for (int v = *version; v < CurrentSchemaVersion(); ++v) {
    MAPD_RETURN_IF_ERROR(Exec(db, "BEGIN IMMEDIATE"));
    Status s = Exec(db, Migrations()[static_cast<size_t>(v)]);
    if (s.ok()) {
      s = Exec(db, "INSERT INTO schema_version (version) VALUES (" + std::to_string(v + 1) + ")");
    }
    if (!s.ok()) {
      (void)Exec(db, "ROLLBACK");
      return Status(s.code(),
                    "migrating schema to version " + std::to_string(v + 1) + ": " + s.message());
    }
    MAPD_RETURN_IF_ERROR(Exec(db, "COMMIT"));
  }
  return Status::Ok();
}

}  // namespace mapd::storage
