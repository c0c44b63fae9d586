// The observation intent on every backend, for the conformance suite: the
// same assertions run on SQLite and on PostgreSQL (a throw-away cluster the
// test starts itself; tests/common/postgres.h).
#ifndef MAPD_TESTS_STORAGE_SUPPORT_OBSERVATION_BACKENDS_H_
#define MAPD_TESTS_STORAGE_SUPPORT_OBSERVATION_BACKENDS_H_

#include <functional>
#include <memory>
#include <string>

#include "common/postgres.h"
#include "common/temp_dir.h"
#include "storage/postgres/observation_log.h"
#include "storage/sqlite/store.h"

namespace mapd::storage::testing {

class ObservationBackend {
 public:
  virtual ~ObservationBackend() = default;
  virtual ObservationReader& reader() = 0;
  // Runs fn in one write transaction, committed when it returns OK and
  // rolled back otherwise.
  virtual Status Write(const std::function<Status(ObservationWriter&)>& fn) = 0;
  // Closes the store and opens it again: what a restart sees.
  virtual Status Reopen() = 0;
};

class SqliteObservationBackend : public ObservationBackend {
 public:
  Status Reopen() override {
    store_.reset();
    StatusOr<std::unique_ptr<SqliteStore>> s = SqliteStore::Open(dir_.File("map.db"), {});
    if (!s.ok()) return s.status();
    store_ = std::move(s).value();
    return Status::Ok();
  }
  ObservationReader& reader() override { return *store_; }
  Status Write(const std::function<Status(ObservationWriter&)>& fn) override {
    StatusOr<std::unique_ptr<WriteTransaction>> txn = store_->BeginWrite();
    if (!txn.ok()) return txn.status();
    MAPD_RETURN_IF_ERROR(fn(**txn));
    return (*txn)->Commit();
  }

 private:
  mapd::testing::TempDir dir_;
  std::unique_ptr<SqliteStore> store_;
};

class PostgresObservationBackend : public ObservationBackend {
 public:
  // A fresh database of the shared cluster; map `map_id` in it.
  PostgresObservationBackend(std::string conninfo, std::string map_id)
      : conninfo_(std::move(conninfo)), map_id_(std::move(map_id)) {}
  Status Reopen() override {
    log_.reset();
    StatusOr<std::unique_ptr<PgObservationLog>> l = PgObservationLog::Open(conninfo_, map_id_);
    if (!l.ok()) return l.status();
    log_ = std::move(l).value();
    return Status::Ok();
  }
  ObservationReader& reader() override { return *log_; }
  Status Write(const std::function<Status(ObservationWriter&)>& fn) override {
    PgWriteScope scope(&log_->writer());
    MAPD_RETURN_IF_ERROR(scope.status());
    std::unique_ptr<PgObservationWriter> w = log_->NewWriter();
    MAPD_RETURN_IF_ERROR(fn(*w));
    MAPD_RETURN_IF_ERROR(w->BeforeCommit());
    MAPD_RETURN_IF_ERROR(scope.Commit());
    w->AfterCommit();
    return Status::Ok();
  }
  const std::string& conninfo() const { return conninfo_; }

 private:
  std::string conninfo_, map_id_;
  std::unique_ptr<PgObservationLog> log_;
};

}  // namespace mapd::storage::testing

#endif  // MAPD_TESTS_STORAGE_SUPPORT_OBSERVATION_BACKENDS_H_
