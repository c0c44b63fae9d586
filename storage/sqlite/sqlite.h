// Thin RAII wrappers over the SQLite C API (SQLiteCpp style, without exceptions).
// Every handle is owned by a unique_ptr with a deleter; failures come back as Status.
#ifndef MAPD_STORAGE_SQLITE_SQLITE_H_
#define MAPD_STORAGE_SQLITE_SQLITE_H_

#include <sqlite3.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "common/status.h"

namespace mapd::storage {

struct SqliteCloser {
  void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
};
struct StmtFinalizer {
  void operator()(sqlite3_stmt* s) const { sqlite3_finalize(s); }
};
using DbHandle = std::unique_ptr<sqlite3, SqliteCloser>;

// A prepared statement. Reset() after each use; bind indexes are 1-based.
class Statement {
 public:
  Statement() = default;
  static StatusOr<Statement> Prepare(sqlite3* db, std::string_view sql);

  Statement& Bind(int i, int64_t v) {
    sqlite3_bind_int64(stmt_.get(), i, v);
    return *this;
  }
  Statement& Bind(int i, double v) {
    sqlite3_bind_double(stmt_.get(), i, v);
    return *this;
  }
  Statement& Bind(int i, std::string_view v) {
    sqlite3_bind_text(stmt_.get(), i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  // The blob must stay alive until the statement is stepped.
  Statement& BindBlob(int i, const void* data, size_t size) {
    sqlite3_bind_blob(stmt_.get(), i, data, static_cast<int>(size), SQLITE_STATIC);
    return *this;
  }
  // SQLITE_ROW or SQLITE_DONE as a bool (true = a row), or the error.
  StatusOr<bool> Step();
  // Runs to completion, then resets. For INSERT/UPDATE/DELETE.
  Status Run();
  void Reset() {
    sqlite3_reset(stmt_.get());
    sqlite3_clear_bindings(stmt_.get());
  }

  int64_t ColumnInt(int i) const { return sqlite3_column_int64(stmt_.get(), i); }
  double ColumnDouble(int i) const { return sqlite3_column_double(stmt_.get(), i); }
  std::string ColumnText(int i) const;
  std::string_view ColumnBlob(int i) const;
  bool ColumnIsNull(int i) const { return sqlite3_column_type(stmt_.get(), i) == SQLITE_NULL; }

 private:
  explicit Statement(sqlite3_stmt* s) : stmt_(s) {}
  std::unique_ptr<sqlite3_stmt, StmtFinalizer> stmt_;
};

// Opens (creating if asked) a database file; `:memory:` works for tests.
StatusOr<DbHandle> OpenDatabase(const std::string& path, bool read_only);
// Runs one or more statements that return no rows.
Status Exec(sqlite3* db, std::string_view sql);
// A SQLite error as a Status naming what we were doing.
Status SqliteError(sqlite3* db, std::string_view what);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_SQLITE_SQLITE_H_
