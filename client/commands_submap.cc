// mapctl submaps | submap upload | merge | global-map
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "client/commands.h"
#include "client/format.h"
#include "client/rigid_transform.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

constexpr size_t kChunkBytes = 1 << 20;  // the API's maximum chunk size

struct SubmapsOptions {
  std::string robot;
  bool json = false;
};

struct UploadOptions {
  std::string path;
  std::string robot;
  std::string name;    // empty: the file name without its extension
  std::string format;  // empty: from the extension
  double resolution = 0;
  std::string session;
};

struct MergeOptions {
  std::vector<uint64_t> ids;
  bool wait = false;
  std::string render;
};

struct GlobalMapOptions {
  std::string output;
  std::string render;
};

std::string Basename(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  const size_t dot = name.find_last_of('.');
  return dot == std::string::npos || dot == 0 ? name : name.substr(0, dot);
}

std::string DescribeSubmap(const pb::SubmapInfo& m) {
  return Printf(
      "submap %llu: robot %s, name %s, resolution %.3f m, %llu occupied / %llu free voxels, "
      "bounds (%.2f, %.2f, %.2f)..(%.2f, %.2f, %.2f) m, %llu bytes",
      static_cast<unsigned long long>(m.id()), m.robot_id().c_str(), m.name().c_str(),
      m.resolution(), static_cast<unsigned long long>(m.occupied_voxels()),
      static_cast<unsigned long long>(m.free_voxels()), m.bounds_min().x(), m.bounds_min().y(),
      m.bounds_min().z(), m.bounds_max().x(), m.bounds_max().y(), m.bounds_max().z(),
      static_cast<unsigned long long>(m.size_bytes()));
}

// Reads a DataChunk stream to its end: the file's bytes, and the info of the first message.
grpc::Status ReadChunks(grpc::ClientReader<pb::DataChunk>* reader, std::string* data,
                        pb::SubmapInfo* info) {
  pb::DataChunk chunk;
  while (reader->Read(&chunk)) {
    if (chunk.has_info()) *info = chunk.info();
    data->append(chunk.data());
  }
  return reader->Finish();
}

RigidTransform ToRigidTransform(const pb::Rigid3& T) {
  return RigidTransform::FromQuaternion(
      T.rotation().w(), T.rotation().x(), T.rotation().y(), T.rotation().z(),
      {T.translation().x(), T.translation().y(), T.translation().z()});
}

std::string FormatMergeProgress(const pb::MergeProgress& p) {
  const double percent = std::floor(100 * std::clamp(p.fraction(), 0.0, 1.0));
  return Printf("merge: %-10s %3.0f%%", p.stage().c_str(), percent);
}

// Per submap: where it sits in the reference (first) submap's frame and the evidence for it.
std::string FormatMergeResult(const pb::MergeResult& result) {
  std::string out = Printf("merge %llu accepted: merged submap %llu\n",
                           static_cast<unsigned long long>(result.merge_id()),
                           static_cast<unsigned long long>(result.merged_submap_id()));
  for (const pb::SubmapAlignment& a : result.alignments()) {
    const RigidTransform T = ToRigidTransform(a.t_reference_submap());
    double yaw = 0, pitch = 0, roll = 0;
    T.YawPitchRollDeg(&yaw, &pitch, &roll);
    out += Printf(
        "  submap %llu: xyz (%.3f, %.3f, %.3f) m, yaw/pitch/roll (%.2f, %.2f, %.2f) deg, "
        "%u matched corners, residual %.3f m, overlap %.2f\n",
        static_cast<unsigned long long>(a.submap_id()), T.t.x, T.t.y, T.t.z, yaw, pitch, roll,
        a.matched_corners(), a.residual_m(), a.overlap_score());
  }
  return out;
}

int RunSubmaps(const Context& ctx, const SubmapsOptions& flags) {
  pb::ListSubmapsRequest request;
  request.set_robot_id(flags.robot);
  pb::ListSubmapsResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListSubmaps(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "submaps", status);
  std::fputs(flags.json ? MessageToJson(response).c_str() : FormatSubmaps(response).c_str(),
             stdout);
  return kExitOk;
}

int RunUpload(const Context& ctx, const UploadOptions& flags) {
  const std::string& path = flags.path;
  pb::SubmapHeader header;
  header.set_robot_id(flags.robot);
  header.set_name(flags.name.empty() ? Basename(path) : flags.name);
  header.set_session_id(flags.session);
  std::string format = flags.format;
  if (format.empty()) format = path.size() > 3 ? path.substr(path.size() - 3) : "";
  if (format == "bt" || format == ".bt")
    header.set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
  else if (format == "ot" || format == ".ot")
    header.set_format(pb::SUBMAP_FORMAT_OCTOMAP_OT);
  else
    return UsageError("submap", "cannot tell the format of '" + path + "': use --format bt|ot");
  header.set_resolution(flags.resolution);
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    PrintError("submap upload: cannot open " + path + ": " + std::strerror(errno));
    return kExitFailed;
  }

  auto call = ctx.NewStreamContext();  // no deadline: large uploads take their time
  pb::SubmapInfo info;
  std::unique_ptr<grpc::ClientWriter<pb::UploadSubmapRequest>> writer =
      ctx.stub->UploadSubmap(call.get(), &info);
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

int RunMerge(const Context& ctx, const MergeOptions& flags) {
  pb::MergeSubmapsRequest request;
  for (uint64_t id : flags.ids) request.add_submap_ids(id);
  if (request.submap_ids_size() < 2) return UsageError("merge", "wants two or more submap ids");
  const std::string& render_path = flags.render;
  ImageFormat render_format = ImageFormat::kPng;
  if (!render_path.empty()) {
    if (int rc = CheckRenderOutput("merge", render_path, &render_format); rc != kContinue)
      return rc;
  }

  auto call = ctx.NewStreamContext();  // no deadline: a merge takes as long as it takes
  std::unique_ptr<grpc::ClientReader<pb::MergeProgress>> reader =
      ctx.stub->MergeSubmaps(call.get(), request);
  pb::MergeProgress progress;
  bool have_result = false;
  pb::MergeResult result;
  std::string last_line;
  while (reader->Read(&progress)) {
    if (progress.has_result()) {
      result = progress.result();
      have_result = true;
    }
    if (!flags.wait) continue;
    // One line per change of stage or whole percent, flushed so that a pipe
    // shows it as it arrives.
    const std::string line = FormatMergeProgress(progress);
    if (line != last_line) {
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
      last_line = line;
    }
  }
  const grpc::Status status = reader->Finish();
  if (status.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
    // The evidence was too weak: the server says why, nothing was written.
    return ReportRpcError(ctx, "merge refused", status);
  }
  if (!status.ok()) return ReportRpcError(ctx, "merge", status);
  if (!have_result) {
    PrintError("merge: the server ended the merge without a result");
    return kExitFailed;
  }
  std::printf("%s", FormatMergeResult(result).c_str());
  std::fflush(stdout);
  if (render_path.empty()) return kExitOk;

  // Each input in its own colour, moved by the transform the merge found:
  // walls that line up show the merge is right.
  std::vector<VoxelLayer> layers;
  for (int i = 0; i < request.submap_ids_size(); ++i) {
    const uint64_t id = request.submap_ids(i);
    const pb::SubmapAlignment* alignment = nullptr;
    for (const pb::SubmapAlignment& a : result.alignments()) {
      if (a.submap_id() == id) alignment = &a;
    }
    RigidTransform T_reference_submap;  // the first input is the reference frame
    if (alignment != nullptr) {
      T_reference_submap = ToRigidTransform(alignment->t_reference_submap());
    } else if (i > 0) {
      PrintError(Printf("merge: no transform for submap %llu in the result; not drawn",
                        static_cast<unsigned long long>(id)));
      continue;
    }
    std::string data;
    pb::SubmapInfo info;
    auto get_call = ctx.NewStreamContext();
    pb::GetSubmapRequest get_request;
    get_request.set_id(id);
    const grpc::Status get_status =
        ReadChunks(ctx.stub->GetSubmap(get_call.get(), get_request).get(), &data, &info);
    if (!get_status.ok()) {
      return ReportRpcError(
          ctx, Printf("merge: GetSubmap %llu", static_cast<unsigned long long>(id)), get_status);
    }
    const std::string what =
        Printf("submap %llu (robot %s, %s)", static_cast<unsigned long long>(id),
               info.robot_id().c_str(), info.name().c_str());
    if (int rc = AddRenderLayer("merge", what, data, T_reference_submap, &layers); rc != kContinue)
      return rc;
  }
  return WriteRendering("merge", layers, render_path, render_format);
}

int RunGlobalMap(const Context& ctx, const GlobalMapOptions& flags) {
  const std::string& output = flags.output;
  const std::string& render_path = flags.render;
  ImageFormat render_format = ImageFormat::kPng;
  if (!render_path.empty()) {
    if (int rc = CheckRenderOutput("global-map", render_path, &render_format); rc != kContinue)
      return rc;
  }
  auto call = ctx.NewStreamContext();
  std::string data;
  pb::SubmapInfo info;
  const grpc::Status status =
      ReadChunks(ctx.stub->GetGlobalMap(call.get(), pb::GetGlobalMapRequest()).get(), &data, &info);
  if (!status.ok()) return ReportRpcError(ctx, "global-map", status);
  std::string error;
  if (!WriteOutput(output, data, &error)) {
    PrintError("global-map: " + error);
    return kExitFailed;
  }
  std::printf("wrote %zu bytes to %s (%s)\n", data.size(), output.c_str(),
              DescribeSubmap(info).c_str());
  std::fflush(stdout);
  if (render_path.empty()) return kExitOk;
  std::vector<VoxelLayer> layers;
  const std::string what =
      Printf("global map (submap %llu)", static_cast<unsigned long long>(info.id()));
  if (int rc = AddRenderLayer("global-map", what, data, RigidTransform(), &layers); rc != kContinue)
    return rc;
  return WriteRendering("global-map", layers, render_path, render_format);
}

}  // namespace

void AddSubmapCommands(CLI::App* app, Action* action) {
  CLI::App* submaps = app->add_subcommand("submaps", "list stored voxel submaps");
  submaps->footer(
      "The stored voxel submaps: id, robot, name, format, resolution, voxel counts, size.");
  auto list = BindCommand(submaps, action, RunSubmaps);
  submaps->add_option("--robot", list->robot, "only this robot's submaps");
  submaps->add_flag("--json", list->json, "the ListSubmapsResponse in protobuf JSON");

  CLI::App* submap =
      app->add_subcommand("submap", "submap upload FILE --robot R: upload an OctoMap file");
  submap->require_subcommand(1);
  CLI::App* upload = submap->add_subcommand("upload", "upload an OctoMap file (.bt or .ot)");
  upload->footer("Uploads the file in 1 MiB chunks and prints the stored submap.");
  auto u = BindCommand(upload, action, RunUpload);
  upload->add_option("FILE", u->path, "the OctoMap file")->required();
  upload->add_option("--robot", u->robot, "the robot that built it")->required();
  upload->add_option("--name", u->name,
                     "unique per robot (default: the file name without its extension)");
  upload->add_option("--format", u->format, "bt or ot (default: from the extension)")
      ->check(CLI::IsMember({"bt", "ot", ".bt", ".ot"}));
  upload->add_option("--resolution", u->resolution, "metres per voxel; 0 = from the file")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  upload->add_option("--session", u->session, "the session frame the submap was built in");

  CLI::App* merge = app->add_subcommand(
      "merge", "merge two or more submaps (--wait: progress, --render: picture)");
  merge->footer(
      "Merges two or more submaps without a prior pose and prints, per submap, where it sits\n"
      "in the first submap's frame (xyz in metres, yaw/pitch/roll in degrees, Z-Y-X), the\n"
      "matched corners, the residual and the overlap score, and the id of the merged map.\n"
      "A merge refused for weak evidence prints the server's reason and exits 1.");
  auto m = BindCommand(merge, action, RunMerge);
  merge->add_option("ID", m->ids, "submap ids (the first is the reference frame)")
      ->required()
      ->expected(2, 1 << 20)
      ->check(PositiveId());
  merge->add_flag(
      "--wait", m->wait,
      "show the progress (stage and percent) while the merge runs (the call always lasts until "
      "the merge ends)");
  merge->add_option(
      "--render", m->render,
      "OUT.png|OUT.svg: after an accepted merge, draw the input submaps from above, each in its "
      "own colour, moved by its transform: walls that line up show the merge is right "
      "(see 'mapctl render --help')");

  CLI::App* global =
      app->add_subcommand("global-map", "download the merged global map (-o FILE.bt, --render)");
  global->footer("Downloads the merged global map (OctoMap binary) to FILE.");
  auto g = BindCommand(global, action, RunGlobalMap);
  global->add_option("-o,--output", g->output, "the .bt file to write")->required();
  global->add_option("--render", g->render,
                     "OUT.png|OUT.svg: also draw it from above (see 'mapctl render --help')");
}

}  // namespace mapd::client
