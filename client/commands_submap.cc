// mapctl submaps | submap upload | merge | global-map
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "client/commands.h"
#include "client/format.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

constexpr size_t kChunkBytes = 1 << 20;  // the API's maximum chunk size

const char kSubmapsHelp[] =
    "Usage: mapctl submaps [--robot R] [--json]\n"
    "The stored voxel submaps: id, robot, name, format, resolution, voxel counts, size.\n";

const char kSubmapHelp[] =
    "Usage: mapctl submap upload FILE --robot R [--name NAME] [--format bt|ot]\n"
    "                            [--resolution M] [--session S]\n"
    "Uploads an OctoMap file (.bt or .ot) in 1 MiB chunks and prints the stored submap.\n"
    "  --name        unique per robot (default: the file name without its extension)\n"
    "  --format      default: from the extension\n"
    "  --resolution  metres per voxel; default 0 = from the file\n"
    "  --session     the session frame the submap was built in\n";

const char kMergeHelp[] =
    "Usage: mapctl merge ID ID... [--wait]\n"
    "Merges two or more submaps without a prior pose and prints the transforms, matched\n"
    "corners, residual and overlap of each, and the id of the merged map.\n"
    "  --wait   print each progress message while the merge runs (the call always lasts\n"
    "           until the merge ends)\n";

const char kGlobalMapHelp[] =
    "Usage: mapctl global-map -o FILE\n"
    "Downloads the merged global map (OctoMap binary) to FILE.\n";

std::string Basename(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

std::string DescribeSubmap(const pb::SubmapInfo& m) {
  return Printf("submap %llu: robot %s, name %s, resolution %.3f m, %llu occupied / %llu free voxels, "
                "bounds (%.2f, %.2f, %.2f)..(%.2f, %.2f, %.2f) m, %llu bytes",
                static_cast<unsigned long long>(m.id()), m.robot_id().c_str(), m.name().c_str(), m.resolution(),
                static_cast<unsigned long long>(m.occupied_voxels()),
                static_cast<unsigned long long>(m.free_voxels()), m.bounds_min().x(), m.bounds_min().y(),
                m.bounds_min().z(), m.bounds_max().x(), m.bounds_max().y(), m.bounds_max().z(),
                static_cast<unsigned long long>(m.size_bytes()));
}

}  // namespace

int RunSubmaps(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("submaps", kSubmapsHelp, args, {{"--robot", true}, {"--json"}}, &flags);
      rc != kContinue) {
    return rc;
  }
  if (!flags.positionals().empty()) return UsageError("submaps", "unexpected argument '" + flags.positionals()[0] + "'");
  pb::ListSubmapsRequest request;
  request.set_robot_id(flags.Get("--robot"));
  pb::ListSubmapsResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListSubmaps(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "submaps", status);
  std::fputs(flags.Has("--json") ? MessageToJson(response).c_str() : FormatSubmaps(response).c_str(), stdout);
  return kExitOk;
}

int RunSubmap(const Context& ctx, const CommandArgs& args) {
  Args flags;
  const std::vector<FlagSpec> specs = {
      {"--robot", true}, {"--name", true}, {"--format", true}, {"--resolution", true}, {"--session", true}};
  if (int rc = ParseCommandArgs("submap", kSubmapHelp, args, specs, &flags); rc != kContinue) return rc;
  const std::vector<std::string>& pos = flags.positionals();
  if (pos.empty() || pos[0] != "upload") return UsageError("submap", "the only subcommand is 'upload FILE'");
  if (pos.size() != 2) return UsageError("submap", "upload wants exactly one FILE");
  if (!flags.Has("--robot")) return UsageError("submap", "upload needs --robot R");
  const std::string path = pos[1];

  pb::SubmapHeader header;
  header.set_robot_id(flags.Get("--robot"));
  header.set_name(flags.Get("--name", Basename(path)));
  header.set_session_id(flags.Get("--session"));
  std::string format = flags.Get("--format");
  if (format.empty()) format = path.size() > 3 ? path.substr(path.size() - 3) : "";
  if (format == "bt" || format == ".bt") header.set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
  else if (format == "ot" || format == ".ot") header.set_format(pb::SUBMAP_FORMAT_OCTOMAP_OT);
  else return UsageError("submap", "cannot tell the format of '" + path + "': use --format bt|ot");
  if (flags.Has("--resolution")) {
    double resolution = 0;
    if (!ParseDouble(flags.Get("--resolution"), &resolution) || resolution < 0) {
      return UsageError("submap", "--resolution wants metres, got '" + flags.Get("--resolution") + "'");
    }
    header.set_resolution(resolution);
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    PrintError("submap upload: cannot open " + path + ": " + std::strerror(errno));
    return kExitFailed;
  }

  grpc::ClientContext call;  // no deadline: large uploads take their time
  pb::SubmapInfo info;
  std::unique_ptr<grpc::ClientWriter<pb::UploadSubmapRequest>> writer = ctx.stub->UploadSubmap(&call, &info);
  pb::UploadSubmapRequest message;
  *message.mutable_header() = header;
  bool open = writer->Write(message);
  std::string chunk(kChunkBytes, '\0');
  while (open && file) {
    file.read(&chunk[0], static_cast<std::streamsize>(chunk.size()));
    const std::streamsize n = file.gcount();
    if (n <= 0) break;
    message.set_chunk(chunk.data(), static_cast<size_t>(n));
    open = writer->Write(message);
  }
  if (open) writer->WritesDone();
  const grpc::Status status = writer->Finish();
  if (!status.ok()) return ReportRpcError(ctx, "submap upload " + path, status);
  std::printf("%s\n", DescribeSubmap(info).c_str());
  return kExitOk;
}

int RunMerge(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("merge", kMergeHelp, args, {{"--wait"}}, &flags); rc != kContinue) return rc;
  pb::MergeSubmapsRequest request;
  for (const std::string& id : flags.positionals()) {
    uint64_t v = 0;
    if (!ParseUint(id, &v) || v == 0) return UsageError("merge", "'" + id + "' is not a submap id");
    request.add_submap_ids(v);
  }
  if (request.submap_ids_size() < 2) return UsageError("merge", "wants two or more submap ids");

  grpc::ClientContext call;  // no deadline: a merge takes as long as it takes
  std::unique_ptr<grpc::ClientReader<pb::MergeProgress>> reader = ctx.stub->MergeSubmaps(&call, request);
  pb::MergeProgress progress;
  bool have_result = false;
  pb::MergeResult result;
  while (reader->Read(&progress)) {
    if (flags.Has("--wait")) std::printf("merge: %-10s %3.0f%%\n", progress.stage().c_str(), 100 * progress.fraction());
    if (progress.has_result()) {
      result = progress.result();
      have_result = true;
    }
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return ReportRpcError(ctx, "merge", status);
  if (!have_result) {
    PrintError("merge: the server ended the merge without a result");
    return kExitFailed;
  }
  std::printf("merge %llu: merged submap %llu\n", static_cast<unsigned long long>(result.merge_id()),
              static_cast<unsigned long long>(result.merged_submap_id()));
  for (const pb::SubmapAlignment& a : result.alignments()) {
    const auto& t = a.t_reference_submap().translation();
    const auto& q = a.t_reference_submap().rotation();
    std::printf("  submap %llu: t = (%.3f, %.3f, %.3f) m, q = (w %.4f, x %.4f, y %.4f, z %.4f), "
                "%u corners, residual %.3f m, overlap %.2f\n",
                static_cast<unsigned long long>(a.submap_id()), t.x(), t.y(), t.z(), q.w(), q.x(), q.y(), q.z(),
                a.matched_corners(), a.residual_m(), a.overlap_score());
  }
  return kExitOk;
}

int RunGlobalMap(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("global-map", kGlobalMapHelp, args, {{"-o", true}, {"--output", true}}, &flags);
      rc != kContinue) {
    return rc;
  }
  const std::string output = flags.Get("-o", flags.Get("--output"));
  if (output.empty()) return UsageError("global-map", "needs -o FILE");
  if (!flags.positionals().empty()) {
    return UsageError("global-map", "unexpected argument '" + flags.positionals()[0] + "'");
  }
  grpc::ClientContext call;
  std::unique_ptr<grpc::ClientReader<pb::DataChunk>> reader = ctx.stub->GetGlobalMap(&call, pb::GetGlobalMapRequest());
  pb::DataChunk chunk;
  std::string data;
  pb::SubmapInfo info;
  while (reader->Read(&chunk)) {
    if (chunk.has_info()) info = chunk.info();
    data += chunk.data();
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return ReportRpcError(ctx, "global-map", status);
  std::string error;
  if (!WriteOutput(output, data, &error)) {
    PrintError("global-map: " + error);
    return kExitFailed;
  }
  std::printf("wrote %zu bytes to %s (%s)\n", data.size(), output.c_str(), DescribeSubmap(info).c_str());
  return kExitOk;
}

}  // namespace mapd::client
