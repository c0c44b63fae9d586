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
#include "service/global_map_builder.h"
#include "service/ingest_batch.h"  // ValidId
#include "service/log.h"
#include "service/merge_runner.h"
#include "service/proto_convert.h"
#include "service/refused_stream.h"
#include "service/status_mapping.h"
#include "service/upload_reactor.h"
#include "voxel/merge.h"  // MergeParams, MergeOutcome (the merge itself: service/voxel_merge.h)
#include "voxel/octree_reader.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

constexpr size_t kChunkBytes = size_t{1} << 20;  // the API's chunk size, both ways
constexpr size_t kMaxNameLength = 256;
// GetGlobalMap waits this long for a build of a change just committed.
constexpr int kGlobalMapWaitMs = 20'000;
// The global map's SubmapInfo.robot_id (like "@merged": not a robot id).
constexpr char kGlobalRobot[] = "@global";

voxel::FusionParams GlobalFusionParams(const SubmapOptions& o) {
  voxel::FusionParams p;
  p.rule = o.log_odds_fusion ? voxel::FusionRule::kLogOdds : voxel::FusionRule::kOverlapRule;
  return p;
}
constexpr char kMagicBt[] = "# Octomap OcTree binary file";
constexpr char kMagicOt[] = "# Octomap OcTree file";

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
  if (h.robot_id().empty()) return InvalidArgument("header.robot_id is required");
  if (!ValidId(h.robot_id()))
    return InvalidArgument("header.robot_id must be 1-128 characters of [A-Za-z0-9_.-]");
  if (h.name().empty()) return InvalidArgument("header.name is required");
  if (!ValidName(h.name()))
    return InvalidArgument("header.name must be 1-256 characters without control characters");
  if (h.format() != pb::SUBMAP_FORMAT_OCTOMAP_BT && h.format() != pb::SUBMAP_FORMAT_OCTOMAP_OT) {
    return InvalidArgument(
        "header.format is required: SUBMAP_FORMAT_OCTOMAP_BT or SUBMAP_FORMAT_OCTOMAP_OT");
  }
  if (!std::isfinite(h.resolution()) || h.resolution() < 0) {
    return InvalidArgument("header.resolution must be finite and >= 0 metres (0 = from the file)");
  }
  if (!h.session_id().empty() && !ValidId(h.session_id())) {
    return InvalidArgument(
        "header.session_id must be 1-128 characters of [A-Za-z0-9_.-] (or empty)");
  }
  return grpc::Status::OK;
}

}  // namespace

SubmapService::SubmapService(Core* core, const SubmapOptions& options, AccessControl* access,
                             std::shared_ptr<MergeRunner> shared_merges)
    : core_(core),
      options_(options),
      access_(access),
      merges_(shared_merges != nullptr
                  ? std::move(shared_merges)
                  : std::make_shared<MergeRunner>(options.max_concurrent_merges,
                                                  options.max_queued_merges,
                                                  options.prepared_submaps_mib << 20)),
      prepared_owner_(merges_->NewOwner()),
      global_(std::make_unique<GlobalMapBuilder>(core, GlobalFusionParams(options))) {}

SubmapService::~SubmapService() {
  // The gRPC server has shut down (every upload is done); store threads may
  // still be returning from Finish.
  std::unique_lock<std::mutex> lock(uploads_mu_);
  uploads_cv_.wait(lock, [this] { return storing_ == 0 && uploads_.empty(); });
  merges_->CloseOwner(prepared_owner_);  // the runner may serve other maps on
}

void SubmapService::StartDraining() {
  draining_ = true;
  merges_->Shutdown();
  global_->Stop();  // after the build in progress: nothing is written later
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
  if (request.id() == 0) return InvalidArgument("id is required");
  return StreamSubmap(context, static_cast<int64_t>(request.id()), writer);
}

grpc::Status SubmapService::GetGlobalMap(grpc::ServerContext* context,
                                         grpc::ServerWriter<pb::DataChunk>* writer) {
  // A change just committed (a merge accepted, an upload) is served once
  // built. Not while the core recovers: nothing is built then, the stored
  // map is served as it is.
  if (core_->CheckReady().ok())
    global_->WaitUntilCurrent(std::chrono::milliseconds(kGlobalMapWaitMs));
  StatusOr<storage::GlobalMapRecord> global = core_->store().GetGlobalMap(/*with_data=*/true);
  if (!global.ok()) {
    const std::string failed = global_->last_error();
    if (global.status().code() == StatusCode::kNotFound && !failed.empty())
      return ToGrpcStatus(Status::FailedPrecondition("the global map was not built: " + failed));
    return ToGrpcStatus(global.status());
  }
  pb::DataChunk chunk;
  pb::SubmapInfo* info = chunk.mutable_info();
  info->set_robot_id(kGlobalRobot);
  info->set_name("global");
  info->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
  info->set_resolution(global->resolution_m);
  info->set_occupied_voxels(global->occupied_voxels);
  info->set_free_voxels(global->free_voxels);
  info->set_size_bytes(global->data.size());
  info->set_created_ns(global->built_ns);
  info->set_merged(true);
  if (StatusOr<voxel::SubmapSummary> summary = voxel::InspectSubmap(global->data); summary.ok()) {
    ToProto(summary->bounds_min, info->mutable_bounds_min());
    ToProto(summary->bounds_max, info->mutable_bounds_max());
  }
  pb::GlobalMapInfo* about = chunk.mutable_global();
  about->set_version(global->version);
  for (const storage::GlobalMapMember& m : global->members) {
    pb::GlobalMapMember* member = about->add_members();
    member->set_submap_id(static_cast<uint64_t>(m.submap_id));
    ToProto(m.T_map_submap, member->mutable_t_map_submap());
  }
  return StreamChunks(context, &chunk, global->data, writer);
}

grpc::Status SubmapService::StreamSubmap(grpc::ServerContext* context, int64_t id,
                                         grpc::ServerWriter<pb::DataChunk>* writer) {
  StatusOr<storage::SubmapMeta> meta = core_->store().GetSubmap(id);
  if (!meta.ok()) return ToGrpcStatus(meta.status());
  StatusOr<std::string> data = core_->store().GetSubmapData(id);
  if (!data.ok()) return ToGrpcStatus(data.status());
  pb::DataChunk chunk;
  ToProto(*meta, chunk.mutable_info());
  return StreamChunks(context, &chunk, *data, writer);
}

grpc::Status SubmapService::StreamChunks(grpc::ServerContext* context, pb::DataChunk* first,
                                         const std::string& bytes,
                                         grpc::ServerWriter<pb::DataChunk>* writer) {
  pb::DataChunk& chunk = *first;
  const std::string* data = &bytes;
  size_t offset = 0;
  do {
    const size_t n = std::min(kChunkBytes, data->size() - offset);
    chunk.set_data(data->data() + offset, n);
    offset += n;
    if (context->IsCancelled() || !writer->Write(chunk)) {
      return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
    }
    chunk.clear_info();
    chunk.clear_global();
  } while (offset < data->size());
  return grpc::Status::OK;
}

grpc::Status SubmapService::Delete(const pb::DeleteSubmapRequest& request,
                                   const Principal& caller) {
  if (request.id() == 0) return InvalidArgument("id is required");
  if (draining_) return ShuttingDown();
  const int64_t id = static_cast<int64_t>(request.id());
  StatusOr<storage::SubmapMeta> meta = core_->store().GetSubmap(id);
  if (!meta.ok()) return ToGrpcStatus(meta.status());
  const std::string target =
      "robot " + meta->robot + " submap " + std::to_string(id) + " '" + meta->name + "'";
  MAPD_RETURN_IF_ERROR_GRPC(
      access_->Check(caller, Permission::kDelete, "DeleteSubmap", meta->robot, target));
  Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    MAPD_RETURN_IF_ERROR(txn->DeleteSubmap(id));
    return txn->AppendAudit(AccessControl::Entry(caller, "DeleteSubmap", target, "ok"));
  });
  if (s.ok()) {
    Log(LogLevel::kInfo, "submap_deleted", {{"id", std::to_string(id)}, {"by", caller.name}});
    merges_->Forget(prepared_owner_, static_cast<uint64_t>(id));
    global_->Invalidate();  // it may have been a member
  }
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

grpc::ServerReadReactor<pb::UploadSubmapRequest>* SubmapService::Upload(
    grpc::CallbackServerContext* context, pb::SubmapInfo* response, StreamSlot slot,
    Principal caller, CallHold hold) {
  using Refused = RefusedStream<grpc::ServerReadReactor<pb::UploadSubmapRequest>>;
  if (draining_) return new Refused(ShuttingDown());
  std::lock_guard<std::mutex> lock(uploads_mu_);
  if (active_uploads_ >= options_.max_concurrent_uploads) {
    Log(LogLevel::kWarn, "upload_refused",
        {{"peer", context->peer()}, {"why", "max_concurrent_uploads"}});
    return new Refused(
        grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                     std::to_string(active_uploads_.load()) +
                         " uploads are in progress (limits.max_concurrent_uploads); retry later"));
  }
  ++active_uploads_;
  auto* reactor = new UploadReactor(this, context, response, std::move(slot), std::move(caller),
                                    std::move(hold));
  uploads_.insert(reactor);
  return reactor;
}

grpc::Status SubmapService::CheckUploadHeader(const pb::UploadSubmapRequest& first,
                                              pb::SubmapHeader* header) {
  if (!first.has_header())
    return InvalidArgument("the first message must be the header (SubmapHeader), not a chunk");
  *header = first.header();
  if (!header->map_id().empty() && header->map_id() != options_.map_id) {
    return InvalidArgument("header.map_id is '" + header->map_id().substr(0, 128) +
                           "' but this upload stream is for map '" + options_.map_id +
                           "'; name the map in the call's mapd-map-id metadata");
  }
  return CheckHeader(*header);
}

grpc::Status SubmapService::AppendUploadChunk(const pb::SubmapHeader& header, size_t index,
                                              pb::UploadSubmapRequest* message,
                                              std::string* bytes) {
  if (message->has_header())
    return InvalidArgument("a second header arrived after the first (message " +
                           std::to_string(index + 1) + ")");
  const std::string& chunk = message->chunk();
  if (chunk.size() > kChunkBytes) {
    return InvalidArgument("chunk " + std::to_string(index) + " has " +
                           std::to_string(chunk.size()) +
                           " bytes; chunks are at most 1 MiB (1048576 bytes)");
  }
  if (bytes->size() + chunk.size() > options_.max_submap_bytes) {
    return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                        "submap '" + header.name() + "' is larger than limits.max_submap_bytes = " +
                            std::to_string(options_.max_submap_bytes) + " bytes");
  }
  if (bytes->empty() && chunk.size() > 0)
    bytes->reserve(std::min(options_.max_submap_bytes, 2 * chunk.size()));
  *bytes += chunk;
  message->clear_chunk();
  return grpc::Status::OK;
}

grpc::Status SubmapService::StoreUpload(const pb::SubmapHeader& header, std::string bytes,
                                        pb::SubmapInfo* response, const Principal& caller) {
  if (bytes.empty()) return InvalidArgument("the upload has a header but no data");

  // The magic line first: a clear message when the header names the other format.
  const bool is_bt = StartsWith(bytes, kMagicBt), is_ot = StartsWith(bytes, kMagicOt);
  if ((header.format() == pb::SUBMAP_FORMAT_OCTOMAP_BT && is_ot) ||
      (header.format() == pb::SUBMAP_FORMAT_OCTOMAP_OT && is_bt)) {
    return InvalidArgument(
        std::string("header.format is ") + FormatName(header.format()) + " but the file is " +
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
    return ToGrpcStatus(
        Status(summary.status().code(), "the submap file is not a valid OctoMap " +
                                            std::string(FormatName(header.format())) +
                                            " within the limits: " + message));
  }
  if (!is_bt && !is_ot)
    return InvalidArgument("the file lacks the OctoMap magic line");  // parser accepted it: a bug
  if (header.resolution() != 0 && std::abs(header.resolution() - summary->resolution) >
                                      1e-9 * std::max(1.0, summary->resolution)) {
    return InvalidArgument("header.resolution " + std::to_string(header.resolution()) +
                           " m does not match the file's " + std::to_string(summary->resolution) +
                           " m");
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
  submap.data = bytes;
  int64_t id = 0;
  Status s = core_->ExecuteWrite([&](storage::WriteTransaction* txn) {
    StatusOr<int64_t> r = txn->InsertSubmap(submap);
    if (!r.ok()) return r.status();
    id = *r;
    return txn->AppendAudit(AccessControl::Entry(
        caller, "UploadSubmap", UploadTarget(header) + " id " + std::to_string(id), "ok"));
  });
  if (!s.ok()) return ToGrpcStatus(s);
  global_->Invalidate();  // an upload in a tied session is a member
  StatusOr<storage::SubmapMeta> stored = core_->store().GetSubmap(id);
  if (!stored.ok()) return ToGrpcStatus(stored.status());
  ToProto(*stored, response);
  Log(LogLevel::kInfo, "submap_stored",
      {{"id", std::to_string(id)},
       {"robot", m.robot},
       {"name", m.name},
       {"bytes", std::to_string(size_bytes)},
       {"occupied", std::to_string(m.occupied_voxels)}});
  // Read and viewed for its merges now, in a free merge slot.
  merges_->PrepareAhead(prepared_owner_, static_cast<uint64_t>(id), std::move(bytes),
                        ToMergeParams(options_));
  return grpc::Status::OK;
}

}  // namespace mapd::service
