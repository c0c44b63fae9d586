// Voxel submaps, the merges that relate them, where accepted merges placed
// them, and the global map built from those placements.
// One intent of storage::Store (storage/store.h).
#ifndef MAPD_STORAGE_SUBMAP_STORE_H_
#define MAPD_STORAGE_SUBMAP_STORE_H_

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "common/status.h"
#include "geometry/rigid3.h"

namespace mapd::storage {

// Robot name under which merged maps are stored. '@' is outside the API's
// robot_id alphabet ([A-Za-z0-9_.-]), so no real robot can collide with it,
// and ListRobots / Counts leave such rows out.
inline constexpr char kMergedRobot[] = "@merged";

enum class SubmapFormat : int { kOctomapBt = 1, kOctomapOt = 2 };  // = mapserver.v1.SubmapFormat

// What is stored about a submap besides its bytes.
struct SubmapMeta {
  int64_t id = 0;
  std::string robot;
  std::string name;
  int64_t session_id = 0;  // 0 = built in no known session frame
  SubmapFormat format = SubmapFormat::kOctomapBt;
  double resolution_m = 0;
  uint64_t occupied_voxels = 0;
  uint64_t free_voxels = 0;
  Eigen::Vector3d bounds_min = Eigen::Vector3d::Zero();  // metres, submap frame
  Eigen::Vector3d bounds_max = Eigen::Vector3d::Zero();
  int64_t created_ns = 0;
  uint64_t size_bytes = 0;
};

// Where an accepted merge placed a submap in the map frame.
struct SubmapPlacement {
  int64_t submap_id = 0;
  int64_t merge_id = 0;
  geometry::Rigid3 T_map_submap;
};

// One submap of the global map and the pose it was fused at.
struct GlobalMapMember {
  int64_t submap_id = 0;
  geometry::Rigid3 T_map_submap;
};

// The global map as built last (service/global_map_builder.h): the union, in
// the map frame, of `members` fused in that order.
struct GlobalMapRecord {
  uint64_t version = 0;  // 1, 2, ... one per change
  int64_t built_ns = 0;
  double resolution_m = 0;
  uint64_t occupied_voxels = 0;
  uint64_t free_voxels = 0;
  std::vector<GlobalMapMember> members;
  std::string data;  // .bt; empty when read without it
};

struct NewSubmap {
  SubmapMeta meta;        // id, session_id and size_bytes are filled in by the store
  std::string session;    // the robot's session the map is built in; empty = none
  std::string_view data;  // the validated file; must outlive InsertSubmap()
};

// A matched corner pair of a merge input (voxel::MatchedCorner), metres.
struct MatchedCornerRecord {
  Eigen::Vector3d in_submap = Eigen::Vector3d::Zero();
  Eigen::Vector3d in_reference = Eigen::Vector3d::Zero();
};

// One input of a merge as recorded. For a refused merge only submap_id is meaningful.
struct MergeInputRecord {
  int64_t submap_id = 0;
  bool aligned = false;                 // the transform and scores below are set
  geometry::Rigid3 T_reference_submap;  // maps the submap into the first input's frame
  int matched_corners = 0;
  double residual_m = 0;
  double overlap_score = 0;
  // The corner pairs behind matched_corners (empty for the first input, and
  // for merges recorded before schema 7).
  std::vector<MatchedCornerRecord> matched;
  // The rest of the placing edge's gate figures (voxel::Alignment): its
  // generator ("" when unknown), support fraction, shared free ratio, restart
  // spread (voxels of the coarser map) and the runner-up's residual (metres);
  // -1 where not measured, and for merges recorded before schema 8.
  std::string source;
  double support_fraction = -1;
  double shared_free_ratio = -1;
  double restart_spread_voxels = -1;
  double second_residual_m = -1;
};

// = mapserver.v1.MergeState. Stored as text ('proposed', ...; MergeStateName).
enum class MergeState : int { kProposed = 1, kAccepted = 2, kRejected = 3, kRefused = 4 };
const char* MergeStateName(MergeState state);  // "proposed", "accepted", ...
// The inverse; unknown text (a newer mapd's state) reads as refused: never in effect.
MergeState ParseMergeState(std::string_view text);

struct MergeRecord {
  int64_t id = 0;
  int64_t created_ns = 0;
  MergeState state = MergeState::kRefused;
  std::string reason;            // refused: the gates' reason; rejected: the operator's
  int64_t merged_submap_id = 0;  // 0 when refused
  std::vector<MergeInputRecord> inputs;
  std::string requested_by;  // who asked for it (empty in databases before schema 6)
  std::string decided_by;    // who approved or rejected it (accepted at once: requested_by)
  int64_t decided_ns = 0;    // 0 while proposed and when refused
};

struct NewMerge {
  MergeRecord record;  // id and merged_submap_id are filled in by the store
  NewSubmap merged;    // accepted merges only: the merged map, stored as a submap
};

struct MergeIds {
  int64_t merge_id = 0;
  int64_t merged_submap_id = 0;
};

// Reads of submaps, merges and the global map. Any thread.
class SubmapReader {
 public:
  virtual ~SubmapReader() = default;
  // Submaps, by id; `robot` empty = all robots (merged maps included).
  virtual StatusOr<std::vector<SubmapMeta>> ListSubmaps(const std::string& robot) = 0;
  virtual StatusOr<SubmapMeta> GetSubmap(int64_t id) = 0;       // NotFound
  virtual StatusOr<std::string> GetSubmapData(int64_t id) = 0;  // the stored file; NotFound
  virtual StatusOr<MergeRecord> GetMerge(int64_t id) = 0;       // NotFound
  virtual StatusOr<std::vector<MergeRecord>> ListMerges() = 0;  // by id
  // Every submap placement, by submap id.
  virtual StatusOr<std::vector<SubmapPlacement>> ListPlacements() = 0;
  // The global map as built last, with its bytes when `with_data`; NotFound
  // before one was built.
  virtual StatusOr<GlobalMapRecord> GetGlobalMap(bool with_data) = 0;
};

// Writes of submaps, merges and the global map, in a WriteTransaction
// (storage/store.h).
class SubmapWriter {
 public:
  virtual ~SubmapWriter() = default;
  // Stores a validated submap. AlreadyExists when the robot has a submap of
  // that name; FailedPrecondition when `session` is given but unknown (the
  // robot must have streamed a batch in it). Creates the robot on first sight.
  virtual StatusOr<int64_t> InsertSubmap(const NewSubmap& submap) = 0;
  // NotFound when there is no such submap. FailedPrecondition when an accepted
  // merge used it as an input or produced it: the merge record and the session
  // frames it tied derive from those bytes, so they stay. Refused merges do
  // not pin their inputs.
  virtual Status DeleteSubmap(int64_t id) = 0;
  // Records a merge. An accepted or proposed one also stores `merged` as a
  // submap of robot kMergedRobot named "merge-<merge id>".
  virtual StatusOr<MergeIds> RecordMerge(const NewMerge& merge) = 0;
  // Ends a proposed merge: kAccepted or kRejected, by `who` at `now_ns`
  // (`reason` for a rejection). NotFound if there is no such merge,
  // FailedPrecondition naming its state if it is not proposed. Ties nothing:
  // the caller ties the sessions in the same transaction.
  virtual Status DecideMerge(int64_t id, MergeState state, const std::string& who, int64_t now_ns,
                             const std::string& reason) = 0;
  // Records where an accepted merge placed a submap in the map frame; a
  // submap placed before keeps its first placement (as a tie is never moved).
  virtual Status PlaceSubmap(int64_t submap_id, int64_t merge_id,
                             const geometry::Rigid3& T_map_submap) = 0;
  // Replaces the global map; DeleteGlobalMap removes it (no member left).
  virtual Status PutGlobalMap(const GlobalMapRecord& map) = 0;
  virtual Status DeleteGlobalMap() = 0;
};

}  // namespace mapd::storage

#endif  // MAPD_STORAGE_SUBMAP_STORE_H_
