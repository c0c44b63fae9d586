// The voxel-submap RPCs of mapserver.v1.MapService: UploadSubmap, ListSubmaps,
// GetSubmap, DeleteSubmap, MergeSubmaps, GetGlobalMap. MapServiceImpl
// delegates to this class; it translates between protobuf and the voxel and
// storage libraries and writes through the Core (core.h: one writer thread).
//
// Rules it implements (see also storage/store.h):
// - Upload (callback API, upload_reactor.h): at most max_concurrent_uploads
//   at once (one more: RESOURCE_EXHAUSTED at once), each ended after
//   upload_idle_timeout_s without data. Header first (robot_id, name, format
//   required), then chunks of at most 1 MiB, at most
//   SubmapOptions::max_submap_bytes in all; the tree may expand to at most
//   max_submap_voxels occupied voxels (counted before anything is built). The bytes are
//   validated by our own depth-limited parser (voxel::InspectSubmap), never by
//   OctoMap's reader directly; the header's format must match the file's magic
//   line and a non-zero header resolution the file's. Only then is it stored.
// - Delete: refused with FAILED_PRECONDITION while an accepted merge uses the
//   submap as an input or produced it.
// - Merge: inputs are uploads; a merged map ("@merged") is refused with
//   INVALID_ARGUMENT before anything runs (it would count its inputs twice,
//   and a proposal's output would be merged unreviewed). Computed by a
//   MergeRunner (max_concurrent_merges at once, at most
//   max_queued_merges waiting, beyond that RESOURCE_EXHAUSTED); progress is
//   streamed as it comes. A refusal (weak evidence, no corners, no overlap,
//   mismatched resolutions, over budget) is recorded as a refused merge with
//   its reason and returned with the library's code (FAILED_PRECONDITION for
//   weak evidence); no merged map is stored. An accepted merge stores the
//   merged map as a submap of robot "@merged" named "merge-<id>", the merge
//   record, and the session ties below, in ONE transaction, and streams the
//   result last. A cancelled call or a server shutdown abandons the merge:
//   nothing is stored.
// - Frames (docs/algorithms.md A.10, Eq. 21): the first input is the reference R. Its
//   session frame's pose in the map, T_map_R, is: R's own if R's session is
//   tied; else T_map_k * T_R_k^-1 from the first input k whose pose in the
//   map is known (its session is tied, or it was uploaded without a session
//   and an accepted merge placed it); else the identity (the reference's frame becomes the map
//   frame: the first tie of a fleet that has no map-frame session yet). Every input i whose session
//   is not tied yet is then tied with T_map_i = T_map_R * T_R_i; ties are never moved later.
//   Submaps uploaded without a session tie nothing. Every input is placed at T_map_R * T_R_i (kept
//   if it was placed before): the global map's members. The fuser then re-projects every stored
//   observation with the new frames, so the robots' walls fuse into one feature map.
// - GetGlobalMap: the union, in the map frame, of every upload with a place
//   there (global_map_builder.h): its session is tied, or an accepted merge
//   placed it (that merge's FramesOfMerge placements). Rebuilt after an
//   accepted merge or approval, an upload and a delete; GetGlobalMap waits
//   up to 20 s for a build in progress. NOT_FOUND before any upload has a
//   place; merged outputs are never members.
// - Review (merge_review.cc): with MergeSubmapsRequest.review or
//   merge.review, a merge the gates accept is stored PROPOSED with its merged
//   map and its audit row, and ties nothing. ApproveMerge, on the writer
//   thread in one transaction, checks that it is still PROPOSED, that its
//   inputs and merged map are still stored and that no merge accepted since
//   it was proposed shares an input submap or a session frame with it
//   (FAILED_PRECONDITION naming which), then marks it ACCEPTED and ties the
//   frames by the rules below, with the frames as they are then.
//   RejectMerge (a reason required) marks it REJECTED. Both are audited, a
//   refused decision too. Every merge records who asked (MergeRecord).
// Built with MAPD_WITH_VOXEL=OFF (no PCL), MergeSubmaps answers
// UNIMPLEMENTED (service/voxel_merge.h); uploads, listing, fetching and
// deleting work in every build (they need only voxel_io).
//
// - Who (access_control.h): an upload's header robot id and a deleted
//   submap's robot are checked against the caller (a robot token touches
//   only its own robot's submaps); uploads, deletes and merges (accepted or
//   refused) are audited in the transaction that stores them.
//
// Thread safety: the handlers may run concurrently on any threads.
#ifndef MAPD_SERVICE_SUBMAP_SERVICE_H_
#define MAPD_SERVICE_SUBMAP_SERVICE_H_

#include <atomic>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_set>
#include <vector>

#include "mapserver/v1/map_service.grpc.pb.h"
#include "service/access_control.h"
#include "service/config.h"
#include "service/core.h"
#include "service/stream_limiter.h"
#include "voxel/merge.h"  // MergeParams (types only)

namespace mapd::service {

class GlobalMapBuilder;
class MergeJob;
class MergeRunner;
class UploadReactor;

// The merge parameters of a map's options (its merges, and its uploads'
// preparation for them).
voxel::MergeParams ToMergeParams(const SubmapOptions& options);

class SubmapService {
 public:
  // `shared_merges`: the merge runner of the server's other maps, so that
  // limits.max_concurrent_merges holds for the whole server (null: its own).
  SubmapService(Core* core, const SubmapOptions& options, AccessControl* access,
                std::shared_ptr<MergeRunner> shared_merges = nullptr);
  const std::shared_ptr<MergeRunner>& merge_runner() const { return merges_; }
  ~SubmapService();

  // Shutdown: new uploads and merges are refused with UNAVAILABLE, merges in
  // flight are abandoned (their handlers return at once).
  void StartDraining();

  // A reactor for one upload (or a refusal: shutdown, too many uploads).
  // `caller` may write (its role was checked); the reactor checks the
  // header's robot id against it before accepting any chunk.
  grpc::ServerReadReactor<mapserver::v1::UploadSubmapRequest>* Upload(
      grpc::CallbackServerContext* context, mapserver::v1::SubmapInfo* response, StreamSlot slot,
      Principal caller, CallHold hold = nullptr);
  // Ends uploads idle for longer than upload_idle_timeout_s (called every second).
  void ExpireIdleUploads();

  // For UploadReactor: the first message, each chunk (appended to `bytes`),
  // and the whole file (validated and stored; fills `response`).
  grpc::Status CheckUploadHeader(const mapserver::v1::UploadSubmapRequest& first,
                                 mapserver::v1::SubmapHeader* header);
  grpc::Status AppendUploadChunk(const mapserver::v1::SubmapHeader& header, size_t index,
                                 mapserver::v1::UploadSubmapRequest* message, std::string* bytes);
  // The audit row of a stored upload is committed with it.
  grpc::Status StoreUpload(const mapserver::v1::SubmapHeader& header, std::string bytes,
                           mapserver::v1::SubmapInfo* response, const Principal& caller);
  // What the audit log names for an upload: "robot R submap 'N'".
  static std::string UploadTarget(const mapserver::v1::SubmapHeader& header);
  AccessControl* access() const { return access_; }
  // Runs `store` on a thread of its own (the destructor waits for it).
  void RunStore(std::function<void()> store);
  void EndUpload(UploadReactor* reactor);  // from its OnDone
  void ReleaseUploadSlot();                // when it finishes (once)
  grpc::Status List(const mapserver::v1::ListSubmapsRequest& request,
                    mapserver::v1::ListSubmapsResponse* response);
  grpc::Status Get(grpc::ServerContext* context, const mapserver::v1::GetSubmapRequest& request,
                   grpc::ServerWriter<mapserver::v1::DataChunk>* writer);
  grpc::Status Delete(const mapserver::v1::DeleteSubmapRequest& request, const Principal& caller);
  grpc::Status Merge(grpc::ServerContext* context,
                     const mapserver::v1::MergeSubmapsRequest& request,
                     grpc::ServerWriter<mapserver::v1::MergeProgress>* writer,
                     const Principal& caller);
  grpc::Status GetGlobalMap(grpc::ServerContext* context,
                            grpc::ServerWriter<mapserver::v1::DataChunk>* writer);
  // Merge records and their review (merge_review.cc); the caller's role was checked.
  grpc::Status ListMerges(const mapserver::v1::ListMergesRequest& request,
                          mapserver::v1::ListMergesResponse* response);
  grpc::Status GetMerge(const mapserver::v1::GetMergeRequest& request,
                        mapserver::v1::MergeRecord* response);
  grpc::Status ApproveMerge(const mapserver::v1::ApproveMergeRequest& request,
                            const Principal& caller, mapserver::v1::MergeRecord* response);
  grpc::Status RejectMerge(const mapserver::v1::RejectMergeRequest& request,
                           const Principal& caller, mapserver::v1::MergeRecord* response);

 private:
  // Approve/Reject's end: audits a refused decision (its own transaction
  // rolled back), or fills `response` with the record as now stored.
  grpc::Status FinishDecision(int64_t id, const Status& outcome,
                              mapserver::v1::MergeRecord* response);
  // Merge's steps (submap_merge.cc).
  struct MergeInputs {
    std::vector<storage::SubmapMeta> metas;
    std::vector<uint64_t> ids;
    std::vector<std::string> bytes;  // moved into the job
  };
  grpc::Status LoadMergeInputs(const mapserver::v1::MergeSubmapsRequest& request,
                               MergeInputs* inputs);
  // Streams the job's progress until its result is there; abandons it when the
  // client goes away or mapd drains (CANCELLED / UNAVAILABLE, nothing stored).
  grpc::Status AwaitMerge(grpc::ServerContext* context, MergeJob* job, size_t inputs,
                          grpc::ServerWriter<mapserver::v1::MergeProgress>* writer);
  // Records the refusal and its reason, audited; returns the library's code.
  grpc::Status RecordRefusedMerge(const std::vector<uint64_t>& ids, const Status& why,
                                  double seconds, const Principal& caller);
  // The merge (accepted or proposed), its audit row and, when accepted, the
  // session ties, in one transaction.
  Status StoreAcceptedMerge(const storage::NewMerge& merge, const MergeInputs& inputs,
                            const std::vector<geometry::Rigid3>& T_ref_input,
                            const Principal& caller, storage::MergeIds* stored, size_t* tied);

  // Streams a stored submap: info on the first chunk, then 1 MiB chunks.
  grpc::Status StreamSubmap(grpc::ServerContext* context, int64_t id,
                            grpc::ServerWriter<mapserver::v1::DataChunk>* writer);
  // Streams `bytes` in 1 MiB chunks, the first one being *first with its data.
  grpc::Status StreamChunks(grpc::ServerContext* context, mapserver::v1::DataChunk* first,
                            const std::string& bytes,
                            grpc::ServerWriter<mapserver::v1::DataChunk>* writer);

  Core* const core_;
  const SubmapOptions options_;
  AccessControl* const access_;
  std::atomic<bool> draining_{false};
  std::shared_ptr<MergeRunner> merges_;
  // This map's token for the views merges_ keeps (MergeRunner::NewOwner).
  const uint64_t prepared_owner_;
  // Keeps the stored global map the union of the placed submaps.
  std::unique_ptr<GlobalMapBuilder> global_;

  std::mutex uploads_mu_;
  std::condition_variable uploads_cv_;
  std::unordered_set<UploadReactor*> uploads_;  // GUARDED_BY(uploads_mu_), admitted, not done
  int storing_ = 0;                             // GUARDED_BY(uploads_mu_), RunStore threads alive
  // Admitted, not finished; incremented under uploads_mu_, decremented
  // without it (from FinishOnce, which ExpireIdleUploads calls under it).
  std::atomic<size_t> active_uploads_{0};
};

}  // namespace mapd::service

#endif  // MAPD_SERVICE_SUBMAP_SERVICE_H_
