// The observation log: robots, their sessions and session frames, and the
// batches they streamed (one row per (robot, session, seq), stored once).
// One intent of storage::Store (storage/store.h).
#ifndef MAPD_STORAGE_OBSERVATION_STORE_H_
#define MAPD_STORAGE_OBSERVATION_STORE_H_

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "common/status.h"
#include "geometry/observation.h"
#include "geometry/rigid3.h"

namespace mapd::storage {

enum class FrameKind : int {
  kMap = 1,    // the session's poses are in the map frame
  kLocal = 2,  // the session has its own frame, tied later by a submap merge
};

// A robot session's frame and how it relates to the map frame.
struct SessionFrame {
  int64_t session_id = 0;
  int64_t robot_id = 0;
  std::string name;  // the robot's name for the session
  FrameKind kind = FrameKind::kMap;
  bool tied = false;             // T_map_frame is known
  geometry::Rigid3 T_map_frame;  // valid when tied
  // Where the tie happened in the commit order (0, 0: tied from the start):
  // the newest observation id committed before it, and the tying
  // transaction's sequence number (1, 2, ...).
  int64_t tied_through_observation = 0;
  int64_t tie_seq = 0;
};

// One batch to store.
struct NewObservation {
  std::string robot;
  std::string session;
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  int64_t received_ns = 0;
  FrameKind frame_kind = FrameKind::kMap;
  const geometry::SensorObservation* features = nullptr;  // pose + lines + planes, sensor frame
};

struct InsertResult {
  bool stored = false;         // false: (robot, session, seq) was stored before
  int64_t observation_id = 0;  // the row id (of the earlier row for a duplicate)
  SessionFrame frame;
};

// A stored observation, as read back.
struct StoredObservation {
  int64_t id = 0;
  int64_t robot_id = 0;
  int64_t session_id = 0;
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  int64_t received_ns = 0;  // when mapd stored it (raw retention counts from here)
  geometry::SensorObservation features;
};

struct StampedPose {
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  geometry::Rigid3 T_frame_sensor;
};

struct RobotSummary {
  int64_t id = 0;
  std::string name;
  int64_t first_seen_ns = 0;
  int64_t last_seen_ns = 0;
  uint64_t batches = 0;
  uint64_t features = 0;
  uint32_t sessions = 0;
  bool all_sessions_tied = false;
};

// One robot session's sensor positions (ObservationReader::ListTrails), session frame.
struct TrailPoint {
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // T_frame_sensor's translation
};
struct SessionTrailRows {
  std::string robot;
  std::string session;
  int64_t session_id = 0;
  uint64_t stored = 0;             // observations stored for the session, before thinning
  std::vector<TrailPoint> points;  // by seq
};

using ObservationFn = std::function<Status(const StoredObservation&)>;

// Reads of the observation log. Any thread.
class ObservationReader {
 public:
  virtual ~ObservationReader() = default;

  // Every stored observation in id (= arrival) order.
  virtual Status ForEachObservation(const ObservationFn& fn) = 0;
  // The stored observations with after_id < id <= through_id, in id order,
  // read in pages: `fn` runs without the reader lock (other reads go on), and
  // rows committed meanwhile past a page are seen (ids only grow).
  virtual Status ForEachObservationBetween(int64_t after_id, int64_t through_id,
                                           const ObservationFn& fn) = 0;
  // The stored observations of `session_ids` with id <= max_id, in id order.
  virtual Status ForEachObservationOfSessions(const std::vector<int64_t>& session_ids,
                                              int64_t max_id, const ObservationFn& fn) = 0;
  // The newest stored observation id (0 if none).
  virtual StatusOr<int64_t> NewestObservationId() = 0;
  virtual StatusOr<std::vector<SessionFrame>> ListSessions() = 0;
  // A committed session by id, or by robot and session name (from a cache).
  virtual StatusOr<SessionFrame> GetSession(int64_t session_id) const = 0;
  virtual StatusOr<SessionFrame> FindSession(const std::string& robot,
                                             const std::string& session) const = 0;
  virtual StatusOr<std::vector<RobotSummary>> ListRobots() = 0;
  // Robot name by id, from a cache (empty if unknown).
  virtual std::string RobotName(int64_t robot_id) const = 0;
  // The sensor poses of a session's newest `limit` observations, newest
  // first, in the session's frame (one index range read).
  virtual StatusOr<std::vector<StampedPose>> RecentPoses(int64_t session_id, int limit) = 0;
  // Every session's stored sensor positions (of `robot`, or of all robots if
  // empty), by robot and session name; a session with more than
  // `max_points` (>= 2) observations is thinned evenly, first and last kept.
  virtual StatusOr<std::vector<SessionTrailRows>> ListTrails(const std::string& robot,
                                                             uint32_t max_points) = 0;
};

// Writes to the observation log, in a WriteTransaction (storage/store.h).
class ObservationWriter {
 public:
  virtual ~ObservationWriter() = default;

  // Inserts one batch unless (robot, session, seq) is stored already. Creates
  // the robot and session on first sight. A batch whose frame kind disagrees
  // with its session's is refused with InvalidArgument; the transaction goes on.
  virtual StatusOr<InsertResult> InsertObservation(const NewObservation& obs) = 0;
  // InsertObservation for each of `batches`, in order, as if one by one:
  // result i is batches[i]'s, an InvalidArgument there being that batch's
  // refusal (the others go on). The outer status fails the transaction. A
  // backend may store them all in one round trip (PostgreSQL does); the
  // default calls InsertObservation.
  virtual StatusOr<std::vector<StatusOr<InsertResult>>> InsertObservations(
      const std::vector<NewObservation>& batches);
  // Ties a session frame to the map frame (T_map_frame). FailedPrecondition
  // if it is tied already: a tie is never moved, so the map stays consistent.
  // The tie is recorded at set_tie_point()'s position in the commit order.
  virtual Status TieSession(int64_t session_id, const geometry::Rigid3& T_map_frame) = 0;
  // The newest observation id committed before this transaction (MapCore sets
  // it before running a write that may tie sessions).
  virtual void set_tie_point(int64_t newest_observation_id) = 0;
  // True once TieSession() succeeded in this transaction.
  virtual bool ties_sessions() const = 0;
  // The sequence number of this transaction's ties (0 if it tied none).
  virtual int64_t tie_seq() const = 0;
  // The sessions TieSession() tied in this transaction, ascending.
  virtual std::vector<int64_t> tied_session_ids() const = 0;
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_OBSERVATION_STORE_H_
