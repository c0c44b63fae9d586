// SqliteStore::RecentPoses: where a robot was last (the web view's robots).
#include <Eigen/Geometry>

#include "storage/sqlite/sqlite.h"
#include "storage/sqlite/store.h"

namespace mapd::storage {

StatusOr<std::vector<StampedPose>> SqliteStore::RecentPoses(int64_t session_id, int limit) {
  std::lock_guard<std::mutex> lock(reader_mu_);
  // UNIQUE (session_id, seq) is an index: this reads `limit` rows, whatever
  // the length of the session.
  StatusOr<Statement> q =
      Statement::Prepare(reader_.get(),
                         "SELECT seq, stamp_ns, qw, qx, qy, qz, tx, ty, tz FROM observations "
                         "WHERE session_id = ?1 ORDER BY seq DESC LIMIT ?2");
  if (!q.ok()) return q.status();
  q->Bind(1, session_id).Bind(2, static_cast<int64_t>(limit));
  std::vector<StampedPose> out;
  for (;;) {
    StatusOr<bool> row = q->Step();
    if (!row.ok()) return row.status();
    if (!*row) break;
    StampedPose p;
    p.seq = static_cast<uint64_t>(q->ColumnInt(0));
    p.stamp_ns = q->ColumnInt(1);
    p.T_frame_sensor.rotation = Eigen::Quaterniond(q->ColumnDouble(2), q->ColumnDouble(3),
                                                   q->ColumnDouble(4), q->ColumnDouble(5));
    p.T_frame_sensor.translation = {q->ColumnDouble(6), q->ColumnDouble(7), q->ColumnDouble(8)};
    out.push_back(p);
  }
  return out;
}

}  // namespace mapd::storage
