// The map server's persistence for ONE map, as a contract: five intents
// (observations, the fused map, submaps and merges, auth and audit,
// snapshots; one header each), read through Store and written through a
// WriteTransaction that spans them all, because a batch, the fused rows it
// changed and the ties a merge implies commit together or not at all.
//
// Implementations: storage/sqlite/ (one database file per map; the embedded
// default). Each passes the same conformance suite (tests/storage/).
//
// Thread safety: BeginWrite(), the WriteTransaction it returns, Checkpoint()
// and ProbeWrite() belong to one writer thread (mapd's writer, which groups
// many robots' batches into one commit). The read methods may be called from
// any thread.
#ifndef MAPD_STORAGE_STORE_H_
#define MAPD_STORAGE_STORE_H_

#include <cstdint>
#include <memory>
#include <string>

#include "common/status.h"
#include "storage/auth_store.h"
#include "storage/fused_map_store.h"
#include "storage/observation_store.h"
#include "storage/snapshot_store.h"
#include "storage/submap_store.h"

namespace mapd::storage {

struct StoreOptions {
  // false: a commit survives a crash of mapd but maybe not of the machine
  // (SQLite synchronous=NORMAL). true: it survives power loss too
  // (synchronous=FULL).
  bool synchronous_full = false;
  // How long a write waits for a lock held by another process (e.g. a backup
  // or an operator's sqlite3 shell) before it fails, milliseconds.
  int busy_timeout_ms = 5000;
  // The database grows to this at most; beyond it writes fail as on a full
  // disk (ResourceExhausted). 0 = no limit, bytes.
  uint64_t max_db_bytes = 0;
};

struct StoreCounts {
  uint64_t robots = 0, sessions = 0, observations = 0, raw_features = 0, fused = 0, submaps = 0;
};

// A group of writes committed together. Rolls back when destroyed unless
// Commit() succeeded.
class WriteTransaction : public ObservationWriter,
                         public FusedMapWriter,
                         public SubmapWriter,
                         public AuthWriter,
                         public SnapshotWriter {
 public:
  ~WriteTransaction() override = default;
  // Durable once this returns OK (per StoreOptions::synchronous_full).
  virtual Status Commit() = 0;
};

class Store : public ObservationReader,
              public FusedMapReader,
              public SubmapReader,
              public AuthReader,
              public SnapshotReader {
 public:
  ~Store() override = default;

  // --- Writer thread only.
  virtual StatusOr<std::unique_ptr<WriteTransaction>> BeginWrite() = 0;
  // Moves written data to its final place and returns freed space (shutdown,
  // idle); for SQLite, a WAL checkpoint.
  virtual Status Checkpoint() = 0;
  // Whether the store takes writes now, after a write failed: for a file,
  // that its file system has room (see the implementation) and a 1 MiB
  // write commits. So a full disk is not declared writable again on its
  // last blocks.
  virtual Status ProbeWrite() = 0;

  // --- Any thread.
  virtual StatusOr<StoreCounts> Counts() = 0;
  // What the store occupies, bytes (for SQLite: the database file plus WAL).
  virtual uint64_t SizeBytes() const = 0;
  // Where the data is, for operators: a file path.
  virtual const std::string& path() const = 0;
  // Whether this store may still write the map's data. Always with a local
  // file; a shared database's store stops once another process took the map
  // over (storage/postgres/map_lease.h), and its writes are refused for good.
  virtual bool owns_map() const { return true; }
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_STORE_H_
