#include "storage/postgres/pq.h"

#include <endian.h>

#include <cstring>

namespace mapd::storage {
namespace {

// Type OIDs (pg_type.h, stable across releases).
constexpr Oid kBoolOid = 16, kByteaOid = 17, kInt8Oid = 20, kInt2Oid = 21, kInt4Oid = 23,
              kTextOid = 25, kFloat8Oid = 701, kInt8ArrayOid = 1016, kFloat8ArrayOid = 1022,
              kByteaArrayOid = 1001, kTextArrayOid = 1009;

void PutBe32(std::string* out, uint32_t v) {
  v = htobe32(v);
  out->append(reinterpret_cast<const char*>(&v), 4);
}
std::string Be64(uint64_t v) {
  v = htobe64(v);
  return std::string(reinterpret_cast<const char*>(&v), 8);
}
uint64_t DoubleBits(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  return bits;
}

}  // namespace

int64_t PgResult::Int(int row, int col) const {
  const char* v = PQgetvalue(result_.get(), row, col);
  switch (PQgetlength(result_.get(), row, col)) {
    case 8: {
      uint64_t x;
      std::memcpy(&x, v, 8);
      return static_cast<int64_t>(be64toh(x));
    }
    case 4: {
      uint32_t x;
      std::memcpy(&x, v, 4);
      return static_cast<int32_t>(be32toh(x));
    }
    case 2: {
      uint16_t x;
      std::memcpy(&x, v, 2);
      return static_cast<int16_t>(be16toh(x));
    }
    case 1:
      return static_cast<unsigned char>(v[0]);
    default:
      return 0;
  }
}

double PgResult::Double(int row, int col) const {
  if (PQgetlength(result_.get(), row, col) != 8) return 0;
  uint64_t x;
  std::memcpy(&x, PQgetvalue(result_.get(), row, col), 8);
  x = be64toh(x);
  double d;
  std::memcpy(&d, &x, 8);
  return d;
}

std::string_view PgResult::Bytes(int row, int col) const {
  return {PQgetvalue(result_.get(), row, col),
          static_cast<size_t>(PQgetlength(result_.get(), row, col))};
}

int64_t PgResult::affected() const {
  const char* n = PQcmdTuples(result_.get());
  return n[0] == '\0' ? 0 : std::strtoll(n, nullptr, 10);
}

PgParams& PgParams::Owned(Oid type, std::string bytes) {
  owned_.push_back(std::make_unique<std::string>(std::move(bytes)));
  types_.push_back(type);
  values_.push_back(owned_.back()->data());
  lengths_.push_back(static_cast<int>(owned_.back()->size()));
  return *this;
}

PgParams& PgParams::Int(int64_t v) { return Owned(kInt8Oid, Be64(static_cast<uint64_t>(v))); }
PgParams& PgParams::Double(double v) { return Owned(kFloat8Oid, Be64(DoubleBits(v))); }
PgParams& PgParams::Bool(bool v) { return Owned(kBoolOid, std::string(1, v ? 1 : 0)); }
PgParams& PgParams::Text(std::string_view v) { return Owned(kTextOid, std::string(v)); }

PgParams& PgParams::Bytes(std::string_view v) {
  types_.push_back(kByteaOid);
  values_.push_back(v.data());
  lengths_.push_back(static_cast<int>(v.size()));
  return *this;
}

PgParams& PgParams::Null() {
  types_.push_back(0);  // let the server infer it
  values_.push_back(nullptr);
  lengths_.push_back(0);
  return *this;
}

// The binary array format: ndim, has-null flag, element type, then per
// dimension its size and lower bound; then per element its length and bytes.
PgParams& PgParams::Array(Oid array_type, Oid element_type,
                          const std::vector<std::string_view>& elements, int element_size) {
  std::string out;
  size_t total = 20;
  for (const std::string_view& e : elements) total += 4 + e.size();
  out.reserve(total);
  PutBe32(&out, 1);
  PutBe32(&out, 0);
  PutBe32(&out, element_type);
  PutBe32(&out, static_cast<uint32_t>(elements.size()));
  PutBe32(&out, 1);
  for (const std::string_view& e : elements) {
    PutBe32(&out, static_cast<uint32_t>(element_size > 0 ? element_size : e.size()));
    out.append(e.data(), e.size());
  }
  return Owned(array_type, std::move(out));
}

PgParams& PgParams::IntArray(const std::vector<int64_t>& v) {
  std::vector<std::string> be;
  be.reserve(v.size());
  for (int64_t x : v) be.push_back(Be64(static_cast<uint64_t>(x)));
  return Array(kInt8ArrayOid, kInt8Oid, {be.begin(), be.end()}, 8);
}

PgParams& PgParams::DoubleArray(const std::vector<double>& v) {
  std::vector<std::string> be;
  be.reserve(v.size());
  for (double x : v) be.push_back(Be64(DoubleBits(x)));
  return Array(kFloat8ArrayOid, kFloat8Oid, {be.begin(), be.end()}, 8);
}

PgParams& PgParams::BytesArray(const std::vector<std::string_view>& v) {
  return Array(kByteaArrayOid, kByteaOid, v, 0);
}
PgParams& PgParams::TextArray(const std::vector<std::string_view>& v) {
  return Array(kTextArrayOid, kTextOid, v, 0);
}

StatusOr<PgConnection> PgConnection::Connect(const std::string& conninfo) {
  PgConnection c;
  c.conn_.reset(PQconnectdb(conninfo.c_str()));
  if (c.conn_ == nullptr) return Status::ResourceExhausted("libpq could not allocate a connection");
  if (PQstatus(c.conn_.get()) != CONNECTION_OK) {
    std::string why = PQerrorMessage(c.conn_.get());
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    return Status::Unavailable("cannot connect to PostgreSQL: " + why);
  }
  // Our messages, not the server's locale; never a silent NOTICE flood.
  MAPD_RETURN_IF_ERROR(c.Exec("SET client_min_messages = warning"));
  return c;
}

Status PgConnection::Exec(const std::string& sql) {
  if (!conn_) return Status::Unavailable("no connection to PostgreSQL (closed)");
  std::unique_ptr<PGresult, PgResultDeleter> r(PQexec(conn_.get(), sql.c_str()));
  const ExecStatusType s = PQresultStatus(r.get());
  if (s == PGRES_COMMAND_OK || s == PGRES_TUPLES_OK) return Status::Ok();
  return PgError(conn_.get(), r.get(), sql.substr(0, 60));
}

StatusOr<PgResult> PgConnection::Query(const std::string& sql, const PgParams& params) {
  if (!conn_) return Status::Unavailable("no connection to PostgreSQL (closed)");
  std::vector<int> formats(params.types_.size(), 1);
  PGresult* r = PQexecParams(conn_.get(), sql.c_str(), params.size(), params.types_.data(),
                             params.values_.data(), params.lengths_.data(), formats.data(),
                             /*resultFormat=*/1);
  PgResult result(r);
  const ExecStatusType s = PQresultStatus(r);
  if (s == PGRES_COMMAND_OK || s == PGRES_TUPLES_OK) return result;
  return PgError(conn_.get(), r, sql.substr(0, 60));
}

Status CheckConninfo(const std::string& conninfo) {
  char* error = nullptr;
  PQconninfoOption* options = PQconninfoParse(conninfo.c_str(), &error);
  if (options == nullptr) {
    std::string why = error != nullptr ? error : "out of memory";
    PQfreemem(error);
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) why.pop_back();
    return Status::InvalidArgument("store: not a PostgreSQL connection string: " + why);
  }
  bool has_password = false;
  for (PQconninfoOption* o = options; o->keyword != nullptr; ++o) {
    if (std::strcmp(o->keyword, "password") == 0 && o->val != nullptr && o->val[0] != '\0')
      has_password = true;
  }
  PQconninfoFree(options);
  if (has_password) {
    return Status::InvalidArgument(
        "store: the connection string holds a password, which others can read on the command "
        "line or in the config file; put it in PGPASSWORD, ~/.pgpass or a file named by "
        "passfile= (mode 0600)");
  }
  return Status::Ok();
}

StatusOr<PgResult> QueryReconnectingOnce(PgConnection& conn, const std::string& conninfo,
                                         const std::string& sql, const PgParams& params) {
  StatusOr<PgResult> r = conn.Query(sql, params);
  if (r.ok() || r.status().code() != StatusCode::kUnavailable) return r;
  StatusOr<PgConnection> again = PgConnection::Connect(conninfo);
  if (!again.ok()) return r;
  conn = std::move(again).value();  // closes the broken one
  return conn.Query(sql, params);
}

Status PgError(PGconn* conn, const PGresult* result, std::string_view what) {
  std::string message = result != nullptr ? PQresultErrorMessage(result) : "";
  if (message.empty() && conn != nullptr) message = PQerrorMessage(conn);
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  const char* state = result != nullptr ? PQresultErrorField(result, PG_DIAG_SQLSTATE) : nullptr;
  const std::string sqlstate = state != nullptr ? state : "";
  std::string text = "PostgreSQL: " + message + " (" + std::string(what) + ")";
  if (sqlstate == "23505") return Status::AlreadyExists(text);
  if (sqlstate == "53100" || sqlstate == "53200" || sqlstate == "53300" || sqlstate == "54000")
    return Status::ResourceExhausted(text);
  if (sqlstate.empty() || sqlstate.rfind("08", 0) == 0 || sqlstate == "40001" ||
      sqlstate == "40P01" || sqlstate == "57P01" || sqlstate == "57P02" || sqlstate == "57P03" ||
      (conn != nullptr && PQstatus(conn) != CONNECTION_OK))
    return Status::Unavailable(text);
  return Status::Internal(text);
}

}  // namespace mapd::storage
