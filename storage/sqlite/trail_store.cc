// Robot trails (GetTrails): the stored sensor positions per session, thinned
// in SQL so that a long session does not travel whole to the reader.
#include <algorithm>

#include "storage/sqlite/store.h"

namespace mapd::storage {

StatusOr<std::vector<SessionTrailRows>> SqliteStore::ListTrails(const std::string& robot,
                                                                uint32_t max_points) {
  const int64_t max_n = std::max<int64_t>(2, max_points);
  std::lock_guard<std::mutex> lock(reader_mu_);
  // rn: 1-based position in the session by seq; n: the session's count. A
  // session longer than ?2 keeps every k-th pose, k = ceil(n / (?2 - 1)),
  // which with the last one is at most ?2 poses.
  StatusOr<Statement> q = Statement::Prepare(
      reader_.get(),
      "SELECT r.name, s.name, s.id, o.seq, o.stamp_ns, o.tx, o.ty, o.tz, o.n FROM "
      "(SELECT session_id, seq, stamp_ns, tx, ty, tz, "
      "row_number() OVER (PARTITION BY session_id ORDER BY seq) AS rn, "
      "count(*) OVER (PARTITION BY session_id) AS n FROM observations "
      // The robot filter inside the window: SQLite does not push the outer
      // WHERE into it, and a full scan would hold the reader lock.
      "WHERE session_id IN (SELECT s2.id FROM sessions s2 JOIN robots r2 ON r2.id = "
      "s2.robot_id WHERE r2.name NOT GLOB '@*' AND (?1 = '' OR r2.name = ?1))) o "
      "JOIN sessions s ON s.id = o.session_id JOIN robots r ON r.id = s.robot_id "
      "WHERE r.name NOT GLOB '@*' AND (?1 = '' OR r.name = ?1) AND "
      "(o.n <= ?2 OR o.rn = o.n OR (o.rn - 1) % ((o.n + ?2 - 2) / (?2 - 1)) = 0) "
      "ORDER BY r.name, s.name, o.seq");
  if (!q.ok()) return q.status();
  q->Bind(1, std::string_view(robot)).Bind(2, max_n);
  std::vector<SessionTrailRows> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) return out;
    const int64_t session_id = q->ColumnInt(2);
    if (out.empty() || out.back().session_id != session_id) {
      SessionTrailRows t;
      t.robot = q->ColumnText(0);
      t.session = q->ColumnText(1);
      t.session_id = session_id;
      t.stored = static_cast<uint64_t>(q->ColumnInt(8));
      out.push_back(std::move(t));
    }
    TrailPoint p;
    p.seq = static_cast<uint64_t>(q->ColumnInt(3));
    p.stamp_ns = q->ColumnInt(4);
    p.position = Eigen::Vector3d(q->ColumnDouble(5), q->ColumnDouble(6), q->ColumnDouble(7));
    out.back().points.push_back(p);
  }
}

}  // namespace mapd::storage
