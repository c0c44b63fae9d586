// Thin RAII wrappers over libpq, without exceptions: a connection, a query's
// parameters and its result, and PostgreSQL errors as Status.
//
// Parameters and results travel in binary format: integers and doubles are
// exact (no text round trip), bytea needs no hex escaping.
#ifndef MAPD_STORAGE_POSTGRES_PQ_H_
#define MAPD_STORAGE_POSTGRES_PQ_H_

#include <libpq-fe.h>

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"

namespace mapd::storage {

struct PgResultDeleter {
  void operator()(PGresult* r) const { PQclear(r); }
};
struct PgConnDeleter {
  void operator()(PGconn* c) const { PQfinish(c); }
};

// The rows of a query, binary format. Accessors check the value's size, so a
// column of an unexpected type reads as 0 / empty rather than past its end.
class PgResult {
 public:
  PgResult() = default;
  explicit PgResult(PGresult* r) : result_(r) {}
  int rows() const { return PQntuples(result_.get()); }
  bool IsNull(int row, int col) const { return PQgetisnull(result_.get(), row, col) != 0; }
  int64_t Int(int row, int col) const;             // int8, int4, int2 or bool
  double Double(int row, int col) const;           // float8
  std::string_view Bytes(int row, int col) const;  // text or bytea, as stored
  std::string Text(int row, int col) const { return std::string(Bytes(row, col)); }
  // The number of rows an INSERT/UPDATE/DELETE touched.
  int64_t affected() const;

 private:
  std::unique_ptr<PGresult, PgResultDeleter> result_;
};

// Query parameters ($1, $2, ...), in binary format.
class PgParams {
 public:
  PgParams& Int(int64_t v);
  PgParams& Double(double v);
  PgParams& Text(std::string_view v);
  // Must outlive the query: only the pointer is kept.
  PgParams& Bytes(std::string_view v);
  PgParams& Bool(bool v);
  PgParams& Null();
  // int8[] and float8[] (one-dimensional, no nulls), for unnest() batches.
  PgParams& IntArray(const std::vector<int64_t>& v);
  PgParams& DoubleArray(const std::vector<double>& v);
  // bytea[] and text[]: the views must outlive the query.
  PgParams& BytesArray(const std::vector<std::string_view>& v);
  PgParams& TextArray(const std::vector<std::string_view>& v);
  int size() const { return static_cast<int>(types_.size()); }

 private:
  friend class PgConnection;
  PgParams& Owned(Oid type, std::string bytes);
  PgParams& Array(Oid array_type, Oid element_type, const std::vector<std::string_view>& elements,
                  int element_size);
  std::vector<Oid> types_;
  std::vector<const char*> values_;
  std::vector<int> lengths_;
  std::vector<std::unique_ptr<std::string>> owned_;  // stable addresses
};

class PgConnection {
 public:
  // Not connected: every statement is Unavailable.
  PgConnection() = default;
  // Connects; Unavailable with libpq's reason when it cannot. The password
  // comes from the connection string, PGPASSWORD or ~/.pgpass (libpq).
  static StatusOr<PgConnection> Connect(const std::string& conninfo);

  // Runs statements that return no rows (several, separated by ';').
  Status Exec(const std::string& sql);
  // Runs one statement with parameters; rows in binary format.
  StatusOr<PgResult> Query(const std::string& sql, const PgParams& params = {});
  bool healthy() const { return conn_ && PQstatus(conn_.get()) == CONNECTION_OK; }
  PGconn* get() const { return conn_.get(); }

 private:
  std::unique_ptr<PGconn, PgConnDeleter> conn_;
};

// Runs one read-only statement (or any statement that is a transaction of
// its own) on `conn`; when the connection has broken (PostgreSQL restarted,
// the network failed: Unavailable), connects to `conninfo` again, replaces
// `conn`, and tries once more. Safe only where running the statement twice
// changes nothing.
StatusOr<PgResult> QueryReconnectingOnce(PgConnection& conn, const std::string& conninfo,
                                         const std::string& sql, const PgParams& params = {});

// Checks a connection string (libpq key=value or postgresql:// URI) before
// use: InvalidArgument with libpq's reason when it does not parse, or when it
// holds a password (command lines and config files are read by others; the
// password belongs in PGPASSWORD, ~/.pgpass or a passfile=).
Status CheckConninfo(const std::string& conninfo);

// A failed result (or connection) as a Status naming `what` we were doing:
// unique violations are AlreadyExists, a full disk or exhausted resources
// ResourceExhausted, a lost connection, shutdown, serialization failure or
// deadlock Unavailable (the caller may retry), anything else Internal. An
// error with no SQLSTATE did not come from the server (libpq's own, e.g.
// "server closed the connection unexpectedly", which libpq does not always
// mark as a broken connection): Unavailable.
Status PgError(PGconn* conn, const PGresult* result, std::string_view what);

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_POSTGRES_PQ_H_
