// mapctl submaps | submap upload|get|delete | global-map (info, crop, transform:
// commands_submap_tools.cc)
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "client/commands.h"
#include "client/format.h"
#include "client/text_util.h"
#include "geometry/rigid3.h"

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

struct GetOptions {
  uint64_t id = 0;
  std::string output;
};

struct DeleteOptions {
  uint64_t id = 0;
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

int RunGet(const Context& ctx, const GetOptions& flags) {
  const std::string what = Printf("submap get %llu", static_cast<unsigned long long>(flags.id));
  pb::GetSubmapRequest request;
  request.set_id(flags.id);
  auto call = ctx.NewStreamContext();  // no deadline: large files take their time
  std::string data;
  pb::SubmapInfo info;
  const grpc::Status status =
      ReadChunks(ctx.stub->GetSubmap(call.get(), request).get(), &data, &info);
  if (!status.ok()) return ReportRpcError(ctx, what, status);
  std::string error;
  if (!WriteOutput(flags.output, data, &error)) {
    PrintError(what + ": " + error);
    return kExitFailed;
  }
  // With -o - the file is on stdout: the description goes to stderr.
  std::fprintf(flags.output == "-" ? stderr : stdout, "wrote %zu bytes to %s (%s)\n", data.size(),
               flags.output.c_str(), DescribeSubmap(info).c_str());
  return kExitOk;
}

int RunDelete(const Context& ctx, const DeleteOptions& flags) {
  pb::DeleteSubmapRequest request;
  request.set_id(flags.id);
  pb::DeleteSubmapResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->DeleteSubmap(call.get(), request, &response);
  if (!status.ok()) {
    return ReportRpcError(
        ctx, Printf("submap delete %llu", static_cast<unsigned long long>(flags.id)), status);
  }
  std::printf("deleted submap %llu\n", static_cast<unsigned long long>(flags.id));
  return kExitOk;
}

// "global map v3: the union of submaps 1, 2, 5 in the map frame".
std::string DescribeGlobalMap(const pb::GlobalMapInfo& global) {
  if (global.version() == 0)
    return "global map: this mapd is older and names no members (its last merge's output)";
  std::string ids;
  for (const pb::GlobalMapMember& m : global.members()) {
    ids += (ids.empty() ? "" : ", ") + std::to_string(m.submap_id());
  }
  return Printf("global map v%llu: the union of submap%s %s in the map frame",
                static_cast<unsigned long long>(global.version()),
                global.members_size() == 1 ? "" : "s", ids.c_str());
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
  pb::GlobalMapInfo global;
  const grpc::Status status = ReadChunks(
      ctx.stub->GetGlobalMap(call.get(), pb::GetGlobalMapRequest()).get(), &data, &info, &global);
  if (!status.ok()) return ReportRpcError(ctx, "global-map", status);
  std::string error;
  if (!WriteOutput(output, data, &error)) {
    PrintError("global-map: " + error);
    return kExitFailed;
  }
  std::printf("wrote %zu bytes to %s (%s)\n", data.size(), output.c_str(),
              DescribeSubmap(info).c_str());
  std::printf("%s\n", DescribeGlobalMap(global).c_str());
  std::fflush(stdout);
  if (render_path.empty()) return kExitOk;
  std::vector<VoxelLayer> layers;
  const std::string what =
      Printf("global map v%llu", static_cast<unsigned long long>(global.version()));
  if (int rc = AddRenderLayer("global-map", what, data, geometry::Rigid3(), &layers);
      rc != kContinue)
    return rc;
  return WriteRendering("global-map", layers, render_path, render_format);
}

}  // namespace

grpc::Status ReadChunks(grpc::ClientReader<pb::DataChunk>* reader, std::string* data,
                        pb::SubmapInfo* info, pb::GlobalMapInfo* global) {
  pb::DataChunk chunk;
  while (reader->Read(&chunk)) {
    if (chunk.has_info()) *info = chunk.info();
    if (chunk.has_global() && global != nullptr) *global = chunk.global();
    data->append(chunk.data());
  }
  return reader->Finish();
}

void AddSubmapCommands(CLI::App* app, Action* action) {
  CLI::App* submaps = app->add_subcommand("submaps", "list stored voxel submaps");
  submaps->footer(
      "The stored voxel submaps: id, robot, name, format, resolution, voxel counts, size.");
  auto list = BindCommand(submaps, action, RunSubmaps);
  submaps->add_option("--robot", list->robot, "only this robot's submaps");
  submaps->add_flag("--json", list->json, "the ListSubmapsResponse in protobuf JSON");

  CLI::App* submap = app->add_subcommand(
      "submap", "submap upload|get|delete|info|crop|transform: one submap or OctoMap file");
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

  CLI::App* get = submap->add_subcommand("get", "download a stored submap (-o FILE.bt|.ot)");
  get->footer("Downloads the submap's file, byte for byte as uploaded (merged maps: .bt).");
  auto gs = BindCommand(get, action, RunGet);
  get->add_option("ID", gs->id, "the submap id (see 'mapctl submaps')")
      ->required()
      ->check(PositiveId());
  get->add_option("-o,--output", gs->output, "the file to write ('-': stdout)")->required();

  CLI::App* del = submap->add_subcommand("delete", "delete a stored submap");
  del->footer(
      "Refused (exit 1) while an accepted merge uses the submap as an input or produced it.");
  auto d = BindCommand(del, action, RunDelete);
  del->add_option("ID", d->id, "the submap id (see 'mapctl submaps')")
      ->required()
      ->check(PositiveId());

  AddSubmapToolCommands(submap, action);

  CLI::App* global = app->add_subcommand(
      "global-map", "download the global map, the union of the placed submaps (-o FILE.bt)");
  global->footer(
      "Downloads the global map (OctoMap binary) to FILE: the union, in the map frame, of every "
      "upload whose place there is known (docs/operations.md, \"The global map\").");
  auto g = BindCommand(global, action, RunGlobalMap);
  global->add_option("-o,--output", g->output, "the .bt file to write")->required();
  global->add_option("--render", g->render,
                     "OUT.png|OUT.svg: also draw it from above (see 'mapctl render --help')");
}

}  // namespace mapd::client
