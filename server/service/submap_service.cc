#include "service/submap_service.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <unordered_set>
#include <utility>
#include <vector>

#include "common/clock.h"
#include "service/log.h"
#include "service/refused_stream.h"
#include "service/status_mapping.h"
#include "service/upload_reactor.h"

#if MAPD_WITH_VOXEL
#include "service/merge_runner.h"
#include "voxel/merge.h"
#else
namespace mapd::service {
class MergeRunner {};  // never made without the voxel library
}  // namespace mapd::service
#endif

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

constexpr size_t kChunkBytes = size_t{1} << 20;  // the API's chunk size, both ways
constexpr size_t kMaxIdLength = 128;             // robot_id, session_id (as in ingest)
constexpr size_t kMaxNameLength = 256;
constexpr char kMagicBt[] = "# Octomap OcTree binary file";
constexpr char kMagicOt[] = "# Octomap OcTree file";

grpc::Status Invalid(const std::string& message) {
  return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, message);
}

void SetVec3(const Eigen::Vector3d& v, pb::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

void ToProto(const storage::SubmapMeta& m, pb::SubmapInfo* out) {
  out->set_id(static_cast<uint64_t>(m.id));
  out->set_robot_id(m.robot);
  out->set_name(m.name);
  out->set_format(m.format == storage::SubmapFormat::kOctomapOt ? pb::SUBMAP_FORMAT_OCTOMAP_OT
                                                                : pb::SUBMAP_FORMAT_OCTOMAP_BT);
  out->set_resolution(m.resolution_m);
  out->set_occupied_voxels(m.occupied_voxels);
  out->set_free_voxels(m.free_voxels);
  SetVec3(m.bounds_min, out->mutable_bounds_min());
  SetVec3(m.bounds_max, out->mutable_bounds_max());
  out->set_size_bytes(m.size_bytes);
  out->set_created_ns(m.created_ns);
}

#define MAPD_RETURN_IF_ERROR_GRPC(expr)              \
  do {                                               \
    if (Status _s = (expr); !_s.ok()) return ToGrpcStatus(_s); \
  } while (0)

grpc::Status ShuttingDown() {
  return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                      "mapd is shutting down; retry after it restarts");
}

#if MAPD_WITH_VOXEL


bool ValidId(const std::string& id) {
  if (id.empty() || id.size() > kMaxIdLength) return false;
  return std::all_of(id.begin(), id.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
  });
}

bool ValidName(const std::string& name) {
  if (name.empty() || name.size() > kMaxNameLength) return false;
  return std::none_of(name.begin(), name.end(),
                      [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
}

const char* FormatName(pb::SubmapFormat f) {
  return f == pb::SUBMAP_FORMAT_OCTOMAP_OT ? "SUBMAP_FORMAT_OCTOMAP_OT (.ot)"
                                           : "SUBMAP_FORMAT_OCTOMAP_BT (.bt)";
}

bool StartsWith(const std::string& bytes, const char* prefix) {
  return bytes.rfind(prefix, 0) == 0;
}

// Checks the header fields (names the field) before any byte is read.
grpc::Status CheckHeader(const pb::SubmapHeader& h) {
  if (h.robot_id().empty()) return Invalid("header.robot_id is required");
  if (!ValidId(h.robot_id()))
    return Invalid("header.robot_id must be 1-128 characters of [A-Za-z0-9_.-]");
  if (h.name().empty()) return Invalid("header.name is required");
  if (!ValidName(h.name()))
    return Invalid("header.name must be 1-256 characters without control characters");
  if (h.format() != pb::SUBMAP_FORMAT_OCTOMAP_BT && h.format() != pb::SUBMAP_FORMAT_OCTOMAP_OT) {
    return Invalid(
        "header.format is required: SUBMAP_FORMAT_OCTOMAP_BT or SUBMAP_FORMAT_OCTOMAP_OT");
  }
  if (!std::isfinite(h.resolution()) || h.resolution() < 0) {
    return Invalid("header.resolution must be finite and >= 0 metres (0 = from the file)");
  }
  if (!h.session_id().empty() && !ValidId(h.session_id())) {
    return Invalid("header.session_id must be 1-128 characters of [A-Za-z0-9_.-] (or empty)");
  }
  return grpc::Status::OK;
}

voxel::MergeParams ToMergeParams(const SubmapOptions& o) {
  voxel::MergeParams p;
  p.min_matched_corners = o.min_matched_corners;
  p.max_residual_voxels = o.max_residual_voxels;
  p.min_overlap_score = o.min_overlap_score;
  p.max_seconds = o.max_merge_seconds;
  p.resolution_policy = o.resample_resolutions ? voxel::ResolutionPolicy::kResampleToFinest
                                               : voxel::ResolutionPolicy::kRefuse;
  p.fusion_rule = o.log_odds_fusion ? voxel::FusionRule::kLogOdds : voxel::FusionRule::kOverlapRule;
  return p;
}

std::string MergeTarget(int64_t merge_id, const std::vector<uint64_t>& ids) {
  std::string s = "merge " + std::to_string(merge_id) + " of submaps";
  for (uint64_t id : ids) s += " " + std::to_string(id);
  return s;
}

geometry::Rigid3 ToRigid(const Eigen::Isometry3d& iso) {
  geometry::Rigid3 T;
  T.rotation = Eigen::Quaterniond(iso.rotation()).normalized();
  T.translation = iso.translation();
  return T;
}

void ToProto(const geometry::Rigid3& T, pb::Rigid3* out) {
  SetVec3(T.translation, out->mutable_translation());
  out->mutable_rotation()->set_w(T.rotation.w());
  out->mutable_rotation()->set_x(T.rotation.x());
  out->mutable_rotation()->set_y(T.rotation.y());
  out->mutable_rotation()->set_z(T.rotation.z());
}

// The library checks its thresholds; this second look keeps a bug there from
// writing a weak merge as a success.
Status CheckEvidence(const voxel::MergeOutcome& outcome,
                     const std::vector<storage::SubmapMeta>& inputs, const SubmapOptions& o) {
  if (outcome.alignments.size() != inputs.size()) {
    return Status::Internal("the merge returned " + std::to_string(outcome.alignments.size()) +
                            " alignments for " + std::to_string(inputs.size()) + " inputs");
  }
  double finest = inputs[0].resolution_m;
  for (const auto& m : inputs) finest = std::min(finest, m.resolution_m);
  for (size_t i = 1; i < outcome.alignments.size(); ++i) {
    const voxel::Alignment& a = outcome.alignments[i];
    const std::string which = "submap " + std::to_string(a.id);
    if (a.matched_corners < o.min_matched_corners) {
      return Status::FailedPrecondition(which + ": " + std::to_string(a.matched_corners) +
                                        " matched corners, merge.min_matched_corners is " +
                                        std::to_string(o.min_matched_corners));
    }
    if (!(a.overlap_score >= o.min_overlap_score)) {
      return Status::FailedPrecondition(
          which + ": overlap score " + std::to_string(a.overlap_score) +
          " below merge.min_overlap_score " + std::to_string(o.min_overlap_score));
    }
    if (!(a.residual_m <= o.max_residual_voxels * finest * (1 + 1e-9))) {
      return Status::FailedPrecondition(which + ": residual " + std::to_string(a.residual_m) +
                                        " m above merge.max_residual_voxels " +
                                        std::to_string(o.max_residual_voxels) + " voxels");
    }
  }
  if (outcome.merged_bt.empty()) return Status::Internal("the merge returned no merged map");
  return Status::Ok();
}

// The session ties an accepted merge implies (see the header comment).
// T_ref_input[i] maps input i into the reference's frame.
StatusOr<std::vector<std::pair<int64_t, geometry::Rigid3>>> FrameTies(
    storage::Store& store, const std::vector<storage::SubmapMeta>& inputs,
    const std::vector<geometry::Rigid3>& T_ref_input) {
  std::vector<std::optional<storage::SessionFrame>> frames(inputs.size());
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (inputs[i].session_id == 0) continue;
    StatusOr<storage::SessionFrame> f = store.GetSession(inputs[i].session_id);
    if (!f.ok()) return f.status();
    frames[i] = *f;
  }
  geometry::Rigid3 T_map_ref = geometry::Rigid3::Identity();
  for (size_t k = 0; k < inputs.size(); ++k) {
    if (frames[k] && frames[k]->tied) {
      T_map_ref = frames[k]->T_map_frame * T_ref_input[k].inverse();
      break;
    }
  }
  std::vector<std::pair<int64_t, geometry::Rigid3>> ties;
  std::unordered_set<int64_t> seen;
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (!frames[i] || frames[i]->tied || !seen.insert(frames[i]->session_id).second) continue;
    ties.emplace_back(frames[i]->session_id, T_map_ref * T_ref_input[i]);
  }
  return ties;
}

#endif  // MAPD_WITH_VOXEL

}  // namespace

SubmapService::SubmapService(MapCore* core, const SubmapOptions& options, AccessControl* access)
    : core_(core), options_(options), access_(access) {
#if MAPD_WITH_VOXEL
  merges_ = std::make_unique<MergeRunner>(options.max_concurrent_merges, options.max_queued_merges);
#endif
}

SubmapService::~SubmapService() {
  // The gRPC server has shut down (every upload is done); store threads may
  // still be returning from Finish.
  std::unique_lock<std::mutex> lock(uploads_mu_);
  uploads_cv_.wait(lock, [this] { return storing_ == 0 && uploads_.empty(); });
}

void SubmapService::StartDraining() {
  draining_ = true;
#if MAPD_WITH_VOXEL
  merges_->Shutdown();
#endif
}

grpc::Status SubmapService::List(const pb::ListSubmapsRequest& request,
                                 pb::ListSubmapsResponse* response) {
  StatusOr<std::vector<storage::SubmapMeta>> submaps =
      core_->store().ListSubmaps(request.robot_id());
  if (!submaps.ok()) return ToGrpcStatus(submaps.status());
  for (const storage::SubmapMeta& m : *submaps) ToProto(m, response->add_submaps());
  return grpc::Status::OK;
}

grpc::Status SubmapService::Get(grpc::ServerContext* context, const pb::GetSubmapRequest& request,
                                grpc::ServerWriter<pb::DataChunk>* writer) {
  if (request.id() == 0) return Invalid("id is required");
  return StreamSubmap(context, static_cast<int64_t>(request.id()), writer);
}

grpc::Status SubmapService::GetGlobalMap(grpc::ServerContext* context,
                                         grpc::ServerWriter<pb::DataChunk>* writer) {
  StatusOr<storage::SubmapMeta> global = core_->store().LatestGlobalMap();
  if (!global.ok()) return ToGrpcStatus(global.status());
  return StreamSubmap(context, global->id, writer);
}

grpc::Status SubmapService::StreamSubmap(grpc::ServerContext* context, int64_t id,
                                         grpc::ServerWriter<pb::DataChunk>* writer) {
  StatusOr<storage::SubmapMeta> meta = core_->store().GetSubmap(id);
  if (!meta.ok()) return ToGrpcStatus(meta.status());
  StatusOr<std::string> data = core_->store().GetSubmapData(id);
  if (!data.ok()) return ToGrpcStatus(data.status());
  pb::DataChunk chunk;
  ToProto(*meta, chunk.mutable_info());
  size_t offset = 0;
  do {
    const size_t n = std::min(kChunkBytes, data->size() - offset);
    chunk.set_data(data->data() + offset, n);
    offset += n;
    if (context->IsCancelled() || !writer->Write(chunk)) {
      return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
    }
    chunk.clear_info();
  } while (offset < data->size());
  return grpc::Status::OK;
}

grpc::Status SubmapService::Delete(const pb::DeleteSubmapRequest& request, const Principal& caller) {
  if (request.id() == 0) return Invalid("id is required");
  if (draining_) return ShuttingDown();
  const int64_t id = static_cast<int64_t>(request.id());
  StatusOr<storage::SubmapMeta> meta = core_->store().GetSubmap(id);
  if (!meta.ok()) return ToGrpcStatus(meta.status());
  const std::string target = "robot " + meta->robot + " submap " + std::to_string(id) + " '" + meta->name + "'";
  MAPD_RETURN_IF_ERROR_GRPC(access_->Check(caller, Permission::kDelete, "DeleteSubmap", meta->robot, target));
  Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    MAPD_RETURN_IF_ERROR(txn->DeleteSubmap(id));
    return txn->AppendAudit(AccessControl::Entry(caller, "DeleteSubmap", target, "ok"));
  });
  if (s.ok()) Log(LogLevel::kInfo, "submap_deleted", {{"id", std::to_string(id)}, {"by", caller.name}});
  return ToGrpcStatus(s);
}

void SubmapService::EndUpload(UploadReactor* reactor) {
  std::lock_guard<std::mutex> lock(uploads_mu_);
  uploads_.erase(reactor);
  uploads_cv_.notify_all();
}

void SubmapService::ReleaseUploadSlot() { active_uploads_.fetch_sub(1); }

void SubmapService::ExpireIdleUploads() {
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(uploads_mu_);
  for (UploadReactor* r : uploads_) r->ExpireIfIdle(now, options_.upload_idle_timeout_s);
}

void SubmapService::RunStore(std::function<void()> store) {
  {
    std::lock_guard<std::mutex> lock(uploads_mu_);
    ++storing_;
  }
  std::thread([this, store = std::move(store)] {
    store();
    std::lock_guard<std::mutex> lock(uploads_mu_);
    --storing_;
    uploads_cv_.notify_all();
  }).detach();
}

std::string SubmapService::UploadTarget(const pb::SubmapHeader& header) {
  return "robot " + header.robot_id() + " submap '" + header.name() + "'";
}

#if !MAPD_WITH_VOXEL

grpc::ServerReadReactor<pb::UploadSubmapRequest>* SubmapService::Upload(grpc::CallbackServerContext*,
                                                                       pb::SubmapInfo*, StreamSlot, Principal) {
  return new RefusedStream<grpc::ServerReadReactor<pb::UploadSubmapRequest>>(grpc::Status(
      grpc::StatusCode::UNIMPLEMENTED,
      "UploadSubmap: this mapd was built without voxel support (MAPD_WITH_VOXEL=OFF)"));
}

grpc::Status SubmapService::CheckUploadHeader(const pb::UploadSubmapRequest&, pb::SubmapHeader*) {
  return grpc::Status(grpc::StatusCode::UNIMPLEMENTED, "built without voxel support");
}
grpc::Status SubmapService::AppendUploadChunk(const pb::SubmapHeader&, size_t, pb::UploadSubmapRequest*,
                                              std::string*) {
  return grpc::Status(grpc::StatusCode::UNIMPLEMENTED, "built without voxel support");
}
grpc::Status SubmapService::StoreUpload(const pb::SubmapHeader&, std::string, pb::SubmapInfo*, const Principal&) {
  return grpc::Status(grpc::StatusCode::UNIMPLEMENTED, "built without voxel support");
}

grpc::Status SubmapService::Merge(grpc::ServerContext*, const pb::MergeSubmapsRequest&,
                                  grpc::ServerWriter<pb::MergeProgress>*, const Principal&) {
  return grpc::Status(
      grpc::StatusCode::UNIMPLEMENTED,
      "MergeSubmaps: this mapd was built without voxel support (MAPD_WITH_VOXEL=OFF)");
}

#else  // MAPD_WITH_VOXEL

grpc::ServerReadReactor<pb::UploadSubmapRequest>* SubmapService::Upload(grpc::CallbackServerContext* context,
                                                                       pb::SubmapInfo* response,
                                                                       StreamSlot slot, Principal caller) {
  using Refused = RefusedStream<grpc::ServerReadReactor<pb::UploadSubmapRequest>>;
  if (draining_) return new Refused(ShuttingDown());
  std::lock_guard<std::mutex> lock(uploads_mu_);
  if (active_uploads_ >= options_.max_concurrent_uploads) {
    Log(LogLevel::kWarn, "upload_refused", {{"peer", context->peer()}, {"why", "max_concurrent_uploads"}});
    return new Refused(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                    std::to_string(active_uploads_.load()) +
                                        " uploads are in progress (limits.max_concurrent_uploads); retry later"));
  }
  ++active_uploads_;
  auto* reactor = new UploadReactor(this, context, response, std::move(slot), std::move(caller));
  uploads_.insert(reactor);
  return reactor;
}

grpc::Status SubmapService::CheckUploadHeader(const pb::UploadSubmapRequest& first, pb::SubmapHeader* header) {
  if (!first.has_header())
    return Invalid("the first message must be the header (SubmapHeader), not a chunk");
  *header = first.header();
  return CheckHeader(*header);
}

grpc::Status SubmapService::AppendUploadChunk(const pb::SubmapHeader& header, size_t index,
                                              pb::UploadSubmapRequest* message, std::string* bytes) {
  if (message->has_header())
    return Invalid("a second header arrived after the first (message " + std::to_string(index + 1) + ")");
  const std::string& chunk = message->chunk();
  if (chunk.size() > kChunkBytes) {
    return Invalid("chunk " + std::to_string(index) + " has " + std::to_string(chunk.size()) +
                   " bytes; chunks are at most 1 MiB (1048576 bytes)");
  }
  if (bytes->size() + chunk.size() > options_.max_submap_bytes) {
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                        "submap '" + header.name() + "' is larger than limits.max_submap_bytes = " +
                            std::to_string(options_.max_submap_bytes) + " bytes");
  }
  if (bytes->empty() && chunk.size() > 0) bytes->reserve(std::min(options_.max_submap_bytes, 2 * chunk.size()));
  *bytes += chunk;
  message->clear_chunk();
  return grpc::Status::OK;
}

grpc::Status SubmapService::StoreUpload(const pb::SubmapHeader& header, std::string bytes,
                                        pb::SubmapInfo* response, const Principal& caller) {
  if (bytes.empty()) return Invalid("the upload has a header but no data");

  // The magic line first: a clear message when the header names the other format.
  const bool is_bt = StartsWith(bytes, kMagicBt), is_ot = StartsWith(bytes, kMagicOt);
  if ((header.format() == pb::SUBMAP_FORMAT_OCTOMAP_BT && is_ot) ||
      (header.format() == pb::SUBMAP_FORMAT_OCTOMAP_OT && is_bt)) {
    return Invalid(std::string("header.format is ") + FormatName(header.format()) +
                   " but the file is " +
                   FormatName(is_bt ? pb::SUBMAP_FORMAT_OCTOMAP_BT : pb::SUBMAP_FORMAT_OCTOMAP_OT));
  }
  // Untrusted bytes: our own iterative, depth- and size-limited parser, which
  // also counts the voxels the tree expands to (limits.max_submap_voxels)
  // without building it.
  voxel::OctreeReadLimits limits;
  limits.max_bytes = std::max<size_t>(limits.max_bytes, options_.max_submap_bytes);
  limits.max_occupied_voxels = options_.max_submap_voxels;
  StatusOr<voxel::SubmapSummary> summary = voxel::InspectSubmap(bytes, limits);
  if (!summary.ok()) {
    Log(LogLevel::kInfo, "submap_refused",
        {{"robot", header.robot_id()},
         {"name", header.name()},
         {"error", summary.status().ToString()}});
    std::string message = summary.status().message();
    if (summary.status().code() == StatusCode::kResourceExhausted &&
        message.find("occupied voxels") != std::string::npos) {
      message += " (limits.max_submap_voxels = " + std::to_string(options_.max_submap_voxels) + ")";
    }
    return ToGrpcStatus(Status(summary.status().code(), "the submap file is not a valid OctoMap " +
                                                            std::string(FormatName(header.format())) +
                                                            " within the limits: " + message));
  }
  if (!is_bt && !is_ot)
    return Invalid("the file lacks the OctoMap magic line");  // parser accepted it: a bug
  if (header.resolution() != 0 && std::abs(header.resolution() - summary->resolution) >
                                      1e-9 * std::max(1.0, summary->resolution)) {
    return Invalid("header.resolution " + std::to_string(header.resolution()) +
                   " m does not match the file's " + std::to_string(summary->resolution) + " m");
  }
  const size_t size_bytes = bytes.size();

  storage::NewSubmap submap;
  storage::SubmapMeta& m = submap.meta;
  m.robot = header.robot_id();
  m.name = header.name();
  m.format = is_ot ? storage::SubmapFormat::kOctomapOt : storage::SubmapFormat::kOctomapBt;
  m.resolution_m = summary->resolution;
  m.occupied_voxels = summary->occupied_voxels;
  m.free_voxels = summary->free_voxels;
  m.bounds_min = summary->bounds_min;
  m.bounds_max = summary->bounds_max;
  m.created_ns = UnixNowNs();
  submap.session = header.session_id();
  submap.data = std::move(bytes);
  int64_t id = 0;
  Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    StatusOr<int64_t> r = txn->InsertSubmap(submap);
    if (!r.ok()) return r.status();
    id = *r;
    return txn->AppendAudit(
        AccessControl::Entry(caller, "UploadSubmap", UploadTarget(header) + " id " + std::to_string(id), "ok"));
  });
  if (!s.ok()) return ToGrpcStatus(s);
  StatusOr<storage::SubmapMeta> stored = core_->store().GetSubmap(id);
  if (!stored.ok()) return ToGrpcStatus(stored.status());
  ToProto(*stored, response);
  Log(LogLevel::kInfo, "submap_stored",
      {{"id", std::to_string(id)},
       {"robot", m.robot},
       {"name", m.name},
       {"bytes", std::to_string(size_bytes)},
       {"occupied", std::to_string(m.occupied_voxels)}});
  return grpc::Status::OK;
}

grpc::Status SubmapService::Merge(grpc::ServerContext* context,
                                  const pb::MergeSubmapsRequest& request,
                                  grpc::ServerWriter<pb::MergeProgress>* writer, const Principal& caller) {
  if (request.submap_ids_size() < 2) return Invalid("submap_ids: give two or more submap ids");
  std::unordered_set<uint64_t> distinct;
  for (uint64_t id : request.submap_ids()) {
    if (id == 0) return Invalid("submap_ids: 0 is not a submap id");
    if (!distinct.insert(id).second)
      return Invalid("submap_ids: " + std::to_string(id) + " is given twice");
  }
  if (draining_) return ShuttingDown();

  std::vector<storage::SubmapMeta> inputs;
  std::vector<uint64_t> ids;
  std::vector<std::string> bytes;
  for (uint64_t id : request.submap_ids()) {
    StatusOr<storage::SubmapMeta> meta = core_->store().GetSubmap(static_cast<int64_t>(id));
    if (!meta.ok()) return ToGrpcStatus(meta.status());
    StatusOr<std::string> data = core_->store().GetSubmapData(static_cast<int64_t>(id));
    if (!data.ok()) return ToGrpcStatus(data.status());
    inputs.push_back(*meta);
    ids.push_back(id);
    bytes.push_back(std::move(data).value());
  }
  const auto t0 = std::chrono::steady_clock::now();
  StatusOr<std::shared_ptr<MergeJob>> submitted =
      merges_->Submit(ids, std::move(bytes), ToMergeParams(options_));
  if (!submitted.ok()) return ToGrpcStatus(submitted.status());
  std::shared_ptr<MergeJob> job = std::move(submitted).value();

  // Stream progress until the result; give up on cancellation or shutdown.
  std::vector<MergeProgressEvent> events;
  bool client_gone = false;
  for (;;) {
    const bool done = job->Wait(std::chrono::milliseconds(50), &events);
    for (const MergeProgressEvent& e : events) {
      pb::MergeProgress progress;
      progress.set_stage(e.stage);
      progress.set_fraction(e.fraction);
      client_gone = client_gone || !writer->Write(progress);
    }
    events.clear();
    if (done) break;
    if (client_gone || context->IsCancelled() || draining_) {
      job->Abandon();
      Log(LogLevel::kInfo, "merge_abandoned",
          {{"inputs", std::to_string(ids.size())},
           {"why", draining_ ? "shutdown" : "client cancelled"}});
      if (draining_) {
        return grpc::Status(
            grpc::StatusCode::UNAVAILABLE,
            "mapd is shutting down; the merge was abandoned and nothing was stored");
      }
      return grpc::Status(grpc::StatusCode::CANCELLED,
                          "the client cancelled the merge; nothing was stored");
    }
  }
  StatusOr<voxel::MergeOutcome> outcome = job->TakeResult();
  if (outcome.ok()) {
    Status evidence = CheckEvidence(*outcome, inputs, options_);
    if (!evidence.ok()) outcome = evidence;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  storage::NewMerge merge;
  merge.record.created_ns = UnixNowNs();
  if (!outcome.ok()) {
    const Status& why = outcome.status();
    if (why.code() == StatusCode::kUnavailable)
      return ToGrpcStatus(why);  // shutdown: nothing to record
    merge.record.accepted = false;
    merge.record.reason = why.ToString();
    for (uint64_t id : ids) {
      storage::MergeInputRecord in;
      in.submap_id = static_cast<int64_t>(id);
      merge.record.inputs.push_back(in);
    }
    int64_t merge_id = 0;
    Status recorded = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
      StatusOr<storage::MergeIds> r = txn->RecordMerge(merge);
      if (!r.ok()) return r.status();
      merge_id = r->merge_id;
      return txn->AppendAudit(AccessControl::Entry(caller, "MergeSubmaps", MergeTarget(r->merge_id, ids),
                                                   "refused: " + why.ToString()));
    });
    Log(LogLevel::kInfo, "merge_refused",
        {{"merge", std::to_string(merge_id)},
         {"inputs", std::to_string(ids.size())},
         {"reason", why.ToString()},
         {"s", std::to_string(seconds)},
         {"recorded", recorded.ok() ? "yes" : recorded.ToString()}});
    return ToGrpcStatus(Status(why.code(), why.message() + " (merge refused; nothing was merged)"));
  }

  // Accepted: alignments in input order, by id.
  std::vector<geometry::Rigid3> T_ref_input(ids.size());
  for (size_t i = 0; i < ids.size(); ++i) {
    const auto it = std::find_if(outcome->alignments.begin(), outcome->alignments.end(),
                                 [&](const voxel::Alignment& a) { return a.id == ids[i]; });
    if (it == outcome->alignments.end()) {
      return grpc::Status(grpc::StatusCode::INTERNAL,
                          "the merge returned no alignment for submap " + std::to_string(ids[i]) +
                              "; nothing was stored");
    }
    T_ref_input[i] = ToRigid(it->T_reference_submap);
    storage::MergeInputRecord in;
    in.submap_id = static_cast<int64_t>(ids[i]);
    in.aligned = true;
    in.T_reference_submap = T_ref_input[i];
    in.matched_corners = it->matched_corners;
    in.residual_m = it->residual_m;
    in.overlap_score = it->overlap_score;
    merge.record.inputs.push_back(in);
  }
  merge.record.accepted = true;
  StatusOr<voxel::SubmapSummary> merged = voxel::InspectSubmap(outcome->merged_bt);
  if (!merged.ok()) {
    return grpc::Status(grpc::StatusCode::INTERNAL, "the merged map does not validate (" +
                                                        merged.status().ToString() +
                                                        "); nothing was stored");
  }
  storage::SubmapMeta& m = merge.merged.meta;
  m.format = storage::SubmapFormat::kOctomapBt;
  m.resolution_m = merged->resolution;
  m.occupied_voxels = merged->occupied_voxels;
  m.free_voxels = merged->free_voxels;
  m.bounds_min = merged->bounds_min;
  m.bounds_max = merged->bounds_max;
  m.created_ns = merge.record.created_ns;
  merge.merged.data = outcome->merged_bt;

  storage::MergeIds stored;
  size_t tied = 0;
  Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    // On the writer thread, so no delete or tie can slip in between these
    // checks and the commit: the inputs still exist, and two merges
    // cannot both tie one session from stale views of the frames.
    for (const storage::SubmapMeta& in : inputs) {
      StatusOr<storage::SubmapMeta> still = core_->store().GetSubmap(in.id);
      if (!still.ok()) {
        return Status::FailedPrecondition("submap " + std::to_string(in.id) +
                                          " was deleted while the merge ran; nothing was stored");
      }
    }
    StatusOr<std::vector<std::pair<int64_t, geometry::Rigid3>>> ties =
        FrameTies(core_->store(), inputs, T_ref_input);
    if (!ties.ok()) return ties.status();
    StatusOr<storage::MergeIds> r = txn->RecordMerge(merge);
    if (!r.ok()) return r.status();
    stored = *r;
    MAPD_RETURN_IF_ERROR(txn->AppendAudit(
        AccessControl::Entry(caller, "MergeSubmaps", MergeTarget(r->merge_id, ids), "ok")));
    for (const auto& [session_id, T_map_frame] : *ties)
      MAPD_RETURN_IF_ERROR(txn->TieSession(session_id, T_map_frame));
    tied = ties->size();
    return Status::Ok();
  });
  if (!s.ok()) return ToGrpcStatus(s);
  Log(LogLevel::kInfo, "merge_accepted",
      {{"merge", std::to_string(stored.merge_id)},
       {"merged_submap", std::to_string(stored.merged_submap_id)},
       {"inputs", std::to_string(ids.size())},
       {"sessions_tied", std::to_string(tied)},
       {"s", std::to_string(seconds)}});

  pb::MergeProgress last;
  last.set_stage("done");
  last.set_fraction(1.0);
  pb::MergeResult* result = last.mutable_result();
  result->set_merge_id(static_cast<uint64_t>(stored.merge_id));
  result->set_merged_submap_id(static_cast<uint64_t>(stored.merged_submap_id));
  for (const storage::MergeInputRecord& in : merge.record.inputs) {
    pb::SubmapAlignment* a = result->add_alignments();
    a->set_submap_id(static_cast<uint64_t>(in.submap_id));
    ToProto(in.T_reference_submap, a->mutable_t_reference_submap());
    a->set_matched_corners(static_cast<uint32_t>(std::max(0, in.matched_corners)));
    a->set_residual_m(in.residual_m);
    a->set_overlap_score(in.overlap_score);
  }
  writer->Write(last);  // stored either way; a client that left can list it
  return grpc::Status::OK;
}

#endif  // MAPD_WITH_VOXEL

}  // namespace mapd::service
