#include "service/global_map_builder.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/clock.h"
#include "service/log.h"
#include "service/merge_review.h"
#include "service/voxel_merge.h"
#include "storage/store.h"

namespace mapd::service {
namespace {

bool SamePose(const geometry::Rigid3& a, const geometry::Rigid3& b) {
  return a.rotation.coeffs() == b.rotation.coeffs() && a.translation == b.translation;
}

struct PlacedUpload {
  geometry::Rigid3 T_map_submap;
  double resolution_m = 0;
};

// The uploads with a place in the map frame, by submap id: the session's tie
// first, else the placement of the merge that placed it.
StatusOr<std::map<int64_t, PlacedUpload>> PlacedUploads(storage::Store& store) {
  StatusOr<std::vector<storage::SubmapMeta>> submaps = store.ListSubmaps("");
  if (!submaps.ok()) return submaps.status();
  StatusOr<std::vector<storage::SubmapPlacement>> placements = store.ListPlacements();
  if (!placements.ok()) return placements.status();
  std::unordered_map<int64_t, geometry::Rigid3> placed;
  for (const storage::SubmapPlacement& p : *placements) placed[p.submap_id] = p.T_map_submap;
  std::map<int64_t, PlacedUpload> out;
  for (const storage::SubmapMeta& m : *submaps) {
    if (m.robot == storage::kMergedRobot) continue;
    if (m.session_id != 0) {
      StatusOr<storage::SessionFrame> frame = store.GetSession(m.session_id);
      if (frame.ok() && frame->tied) {
        out[m.id] = {frame->T_map_frame, m.resolution_m};
        continue;
      }
    }
    if (auto it = placed.find(m.id); it != placed.end()) out[m.id] = {it->second, m.resolution_m};
  }
  return out;
}

// Databases from before the placements table (schema 11) have accepted
// merges without them: each gets the placements its acceptance would record
// now (FramesOfMerge), once; a placement never moves (INSERT OR IGNORE).
Status BackfillPlacements(Core* core) {
  storage::Store& store = core->store();
  StatusOr<std::vector<storage::SubmapPlacement>> placements = store.ListPlacements();
  if (!placements.ok()) return placements.status();
  std::unordered_map<int64_t, int64_t> placed;
  for (const storage::SubmapPlacement& p : *placements) placed[p.submap_id] = p.merge_id;
  StatusOr<std::vector<storage::MergeRecord>> merges = store.ListMerges();
  if (!merges.ok()) return merges.status();
  for (const storage::MergeRecord& merge : *merges) {
    if (merge.state != storage::MergeState::kAccepted) continue;
    bool missing = false;
    for (const storage::MergeInputRecord& in : merge.inputs)
      missing = missing || (in.aligned && placed.count(in.submap_id) == 0);
    if (!missing) continue;
    std::vector<storage::SubmapMeta> metas;
    std::vector<geometry::Rigid3> T_ref_input;
    for (const storage::MergeInputRecord& in : merge.inputs) {
      StatusOr<storage::SubmapMeta> meta = store.GetSubmap(in.submap_id);
      if (!meta.ok()) return meta.status();  // an accepted merge's inputs are kept
      metas.push_back(*std::move(meta));
      T_ref_input.push_back(in.T_reference_submap);
    }
    const Status written = core->ExecuteWrite([&](storage::WriteTransaction* txn) -> Status {
      StatusOr<MergeFrames> frames = FramesOfMerge(store, metas, T_ref_input);
      if (!frames.ok()) return frames.status();
      for (const auto& [submap_id, T_map_submap] : frames->placements)
        MAPD_RETURN_IF_ERROR(txn->PlaceSubmap(submap_id, merge.id, T_map_submap));
      return Status::Ok();
    });
    MAPD_RETURN_IF_ERROR(written);
    for (const storage::MergeInputRecord& in : merge.inputs) placed[in.submap_id] = merge.id;
  }
  return Status::Ok();
}

}  // namespace

GlobalMapBuilder::GlobalMapBuilder(Core* core, voxel::FusionParams params)
    : core_(core), params_(params), worker_([this] { Loop(); }) {}

GlobalMapBuilder::~GlobalMapBuilder() { Stop(); }

void GlobalMapBuilder::Invalidate() {
  std::lock_guard<std::mutex> lock(mu_);
  ++requested_;
  cv_.notify_all();
}

bool GlobalMapBuilder::WaitUntilCurrent(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  const uint64_t wanted = requested_;
  return cv_.wait_for(lock, timeout, [&] { return built_ >= wanted || stop_; }) && built_ >= wanted;
}

std::string GlobalMapBuilder::last_error() const {
  std::lock_guard<std::mutex> lock(mu_);
  return last_error_;
}

void GlobalMapBuilder::Stop() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
    cv_.notify_all();
  }
  if (worker_.joinable()) worker_.join();
}

void GlobalMapBuilder::Loop() {
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    cv_.wait_for(lock, std::chrono::milliseconds(100),
                 [&] { return stop_ || requested_ > built_; });
    if (stop_) return;
    if (requested_ <= built_) continue;
    lock.unlock();
    const bool ready = core_->CheckReady().ok();
    lock.lock();
    if (!ready) {
      // Writes are refused while the core recovers: the build waits, asking
      // again every 100 ms (not in a spin: recovery needs the CPU).
      cv_.wait_for(lock, std::chrono::milliseconds(100), [&] { return stop_.load(); });
      continue;
    }
    const uint64_t covering = requested_;
    const bool first = !backfilled_;
    lock.unlock();
    Status built = first ? BackfillPlacements(core_) : Status::Ok();
    if (built.ok()) built = BuildOnce();
    if (stop_ && built.code() == StatusCode::kUnavailable) {
      // Nothing was stored: the next start finds the members changed and
      // builds again. Not counted as built, so no waiter takes it for one.
      Log(LogLevel::kInfo, "global_map_abandoned", {{"why", "shutdown"}});
      return;
    }
    if (!built.ok() && built.code() != StatusCode::kUnimplemented) {
      Log(LogLevel::kError, "global_map_failed", {{"error", built.ToString()}});
    }
    lock.lock();
    last_error_ = built.ok() ? "" : built.message();
    backfilled_ = backfilled_ || built.ok();
    built_ = covering;
    cv_.notify_all();
  }
}

Status GlobalMapBuilder::BuildOnce() {
  storage::Store& store = core_->store();
  StatusOr<std::map<int64_t, PlacedUpload>> wanted = PlacedUploads(store);
  if (!wanted.ok()) return wanted.status();
  StatusOr<storage::GlobalMapRecord> previous = store.GetGlobalMap(/*with_data=*/true);
  if (!previous.ok() && previous.status().code() != StatusCode::kNotFound) return previous.status();
  const bool had_map = previous.ok();

  // The members in joining order: the old ones that stay, then the new ones
  // by id. Incremental when no old one left or moved, and no new one is
  // finer than the map (it would lose detail in the map's grid).
  std::vector<storage::GlobalMapMember> members;
  bool incremental = had_map;
  if (had_map) {
    for (const storage::GlobalMapMember& m : previous->members) {
      auto it = wanted->find(m.submap_id);
      if (it == wanted->end() || !SamePose(it->second.T_map_submap, m.T_map_submap)) {
        incremental = false;
        continue;
      }
      members.push_back({m.submap_id, m.T_map_submap});
      wanted->erase(it);
    }
  }
  const size_t kept = members.size();
  for (const auto& [id, placed] : *wanted) {
    members.push_back({id, placed.T_map_submap});
    if (had_map && placed.resolution_m < previous->resolution_m) incremental = false;
  }
  if (incremental && members.size() == kept) return Status::Ok();  // nothing changed

  if (members.empty()) {
    if (!had_map) return Status::Ok();
    return core_->ExecuteWrite(
        [](storage::WriteTransaction* txn) { return txn->DeleteGlobalMap(); });
  }
  // The bytes of the members to fuse (held only for this build).
  const size_t first = incremental ? kept : 0;
  std::vector<std::string> bytes;
  bytes.reserve(members.size() - first);
  std::vector<voxel::PlacedSubmap> fuse;
  for (size_t i = first; i < members.size(); ++i) {
    if (stop_) return Status::Unavailable("the global map build was stopped");
    StatusOr<std::string> data = store.GetSubmapData(members[i].submap_id);
    if (!data.ok()) return data.status();
    bytes.push_back(*std::move(data));
  }
  for (size_t i = first; i < members.size(); ++i) {
    fuse.push_back({static_cast<uint64_t>(members[i].submap_id),
                    members[i].T_map_submap.ToIsometry(), bytes[i - first]});
  }
  const auto start = std::chrono::steady_clock::now();
  StatusOr<voxel::GlobalMapBuild> build = ExtendVoxelGlobalMap(
      incremental ? std::string_view(previous->data) : std::string_view(), fuse, params_, &stop_);
  if (!build.ok()) return build.status();
  storage::GlobalMapRecord record;
  record.version = had_map ? previous->version + 1 : 1;
  record.built_ns = UnixNowNs();
  record.resolution_m = build->resolution_m;
  record.occupied_voxels = build->occupied_voxels;
  record.free_voxels = build->free_voxels;
  record.members = std::move(members);
  record.data = std::move(build->bt);
  Log(LogLevel::kInfo, "global_map_built",
      {{"version", std::to_string(record.version)},
       {"members", std::to_string(record.members.size())},
       {"fused", std::to_string(fuse.size())},
       {"incremental", incremental ? "true" : "false"},
       {"occupied_voxels", std::to_string(record.occupied_voxels)},
       {"s",
        std::to_string(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count())}});
  return core_->ExecuteWrite(
      [&record](storage::WriteTransaction* txn) { return txn->PutGlobalMap(record); });
}

}  // namespace mapd::service
