// The backend-neutral helpers of the storage contract (storage/*_store.h).
#include "storage/fused_map_store.h"
#include "storage/observation_store.h"
#include "storage/snapshot_store.h"
#include "storage/submap_store.h"

namespace mapd::storage {

Status FusedMapWriter::WriteFused(const std::vector<FusedRow>& upserts,
                                  const std::vector<uint64_t>& deletes) {
  for (const FusedRow& row : upserts) MAPD_RETURN_IF_ERROR(UpsertFused(row));
  for (uint64_t id : deletes) MAPD_RETURN_IF_ERROR(DeleteFused(id));
  return Status::Ok();
}

Status FusedMapWriter::WriteFusedPlanes(const std::vector<FusedPlaneRow>& upserts,
                                        const std::vector<uint64_t>& deletes) {
  for (const FusedPlaneRow& row : upserts) MAPD_RETURN_IF_ERROR(UpsertFusedPlane(row));
  for (uint64_t id : deletes) MAPD_RETURN_IF_ERROR(DeleteFusedPlane(id));
  return Status::Ok();
}

StatusOr<std::vector<StatusOr<InsertResult>>> ObservationWriter::InsertObservations(
    const std::vector<NewObservation>& batches) {
  std::vector<StatusOr<InsertResult>> results;
  results.reserve(batches.size());
  for (const NewObservation& obs : batches) {
    StatusOr<InsertResult> r = InsertObservation(obs);
    if (!r.ok() && r.status().code() != StatusCode::kInvalidArgument) return r.status();
    results.push_back(std::move(r));
  }
  return results;
}

const char* MergeStateName(MergeState state) {
  switch (state) {
    case MergeState::kProposed:
      return "proposed";
    case MergeState::kAccepted:
      return "accepted";
    case MergeState::kRejected:
      return "rejected";
    case MergeState::kRefused:
      return "refused";
  }
  return "refused";
}

MergeState ParseMergeState(std::string_view text) {
  for (MergeState s : {MergeState::kProposed, MergeState::kAccepted, MergeState::kRejected}) {
    if (text == MergeStateName(s)) return s;
  }
  return MergeState::kRefused;
}

std::vector<std::string_view> SnapshotPartsOf(const FusionSnapshot& snapshot, size_t part_bytes) {
  std::vector<std::string_view> out;
  for (const std::string* bytes : {&snapshot.state, &snapshot.plane_state}) {
    const std::string_view all(*bytes);
    for (size_t at = 0; at < all.size(); at += part_bytes)
      out.push_back(all.substr(at, part_bytes));
  }
  return out;
}

}  // namespace mapd::storage
