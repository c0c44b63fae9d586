// mapctl submap info | crop | transform: the voxel tools operators reach for,
// on a local OctoMap file (no server needed) or a stored submap's bytes. Every
// file goes through the server's own validating reader (voxel_io).
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include "client/commands.h"
#include "client/format.h"
#include "client/text_util.h"
#include "voxel/map_edit.h"
#include "voxel/octree_reader.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct InfoOptions {
  std::string what;  // a file, or a stored submap's id
};

struct CropOptions {
  std::string what;
  std::vector<double> min_m, max_m;  // x, y, z each
  std::string output;
};

struct TransformOptions {
  std::string what;
  std::vector<double> translate_m = {0, 0, 0};  // x, y, z
  std::vector<double> rotate_deg = {0, 0, 0};   // yaw, pitch, roll
  std::string output;
};

// The bytes of FILE|ID: a local file when one exists at that path, else a
// stored submap when it is all digits. `label` names it in messages. Returns
// kContinue, or the exit code (the error printed).
int ReadMapBytes(const Context& ctx, const std::string& command, const std::string& what,
                 std::string* bytes, std::string* label) {
  struct stat st {};
  if (stat(what.c_str(), &st) == 0) {
    if (!S_ISREG(st.st_mode)) {
      PrintError(command + ": " + what + " is not a regular file");
      return kExitFailed;
    }
    std::ifstream file(what, std::ios::binary);
    if (!file) {
      PrintError(command + ": cannot open " + what + ": " + std::strerror(errno));
      return kExitFailed;
    }
    bytes->assign(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
    *label = what;
    return kContinue;
  }
  if (what.empty() ||
      !std::all_of(what.begin(), what.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return UsageError("submap",
                      "'" + what + "' is neither a file nor a submap id (see 'mapctl submaps')");
  }
  pb::GetSubmapRequest request;
  request.set_id(std::strtoull(what.c_str(), nullptr, 10));
  auto call = ctx.NewStreamContext();
  pb::SubmapInfo info;
  const grpc::Status status =
      ReadChunks(ctx.stub->GetSubmap(call.get(), request).get(), bytes, &info);
  if (!status.ok()) return ReportRpcError(ctx, command + " " + what, status);
  *label = "submap " + what + " (robot " + info.robot_id() + ", name " + info.name() + ")";
  return kContinue;
}

std::string Describe(const std::string& label, const std::string& bytes,
                     const voxel::SubmapSummary& summary) {
  const bool full = bytes.rfind("# Octomap OcTree file", 0) == 0;
  const Eigen::Vector3d extent = summary.bounds_max - summary.bounds_min;
  return Printf(
      "%s: OctoMap %s, resolution %.3f m, %llu occupied / %llu free voxels, occupied within "
      "(%.2f, %.2f, %.2f)..(%.2f, %.2f, %.2f) m (%.2f x %.2f x %.2f m), %zu bytes",
      label.c_str(), full ? ".ot" : ".bt", summary.resolution,
      static_cast<unsigned long long>(summary.occupied_voxels),
      static_cast<unsigned long long>(summary.free_voxels), summary.bounds_min.x(),
      summary.bounds_min.y(), summary.bounds_min.z(), summary.bounds_max.x(),
      summary.bounds_max.y(), summary.bounds_max.z(), extent.x(), extent.y(), extent.z(),
      bytes.size());
}

// mapctl submap info FILE|ID: what an OctoMap file holds, read with the
// server's own validating reader (no tree is built).
int RunInfo(const Context& ctx, const InfoOptions& flags) {
  std::string bytes, label;
  if (int rc = ReadMapBytes(ctx, "submap info", flags.what, &bytes, &label); rc != kContinue)
    return rc;
  const StatusOr<voxel::SubmapSummary> summary = voxel::InspectSubmap(bytes);
  if (!summary.ok()) {
    PrintError("submap info: " + label +
               " is not a usable OctoMap file: " + summary.status().message());
    return kExitFailed;
  }
  std::printf("%s\n", Describe(label, bytes, *summary).c_str());
  return kExitOk;
}

// The output's format from its name: .bt or .ot. kContinue, or the exit code.
int CheckEditOutput(const std::string& command, const std::string& path, bool* full) {
  const auto ends_with = [&](const char* suffix) {
    const size_t n = std::strlen(suffix);
    return path.size() > n && path.compare(path.size() - n, n, suffix) == 0;
  };
  if (ends_with(".bt")) {
    *full = false;
  } else if (ends_with(".ot")) {
    *full = true;
  } else {
    return UsageError(command, "the output '" + path + "' must end in .bt or .ot");
  }
  return kContinue;
}

// Reads FILE|ID into a tree, applies `edit`, writes `output` and describes
// it. Malformed input is kExitUsage (as render); an edit the map cannot take
// (an empty box, a map moved out of range) kExitFailed, with the reason.
template <typename Edit>
int RunEdit(const Context& ctx, const std::string& command, const std::string& what,
            const std::string& output, const Edit& edit) {
  bool full = false;
  if (int rc = CheckEditOutput(command, output, &full); rc != kContinue) return rc;
  std::string bytes, label;
  if (int rc = ReadMapBytes(ctx, command, what, &bytes, &label); rc != kContinue) return rc;
  StatusOr<voxel::OcTreePtr> tree = voxel::ReadOctree(bytes);
  if (!tree.ok()) {
    PrintError(command + ": " + label +
               " is not a usable OctoMap file: " + tree.status().message());
    return kExitUsage;
  }
  StatusOr<voxel::OcTreePtr> edited = edit(**tree);
  if (!edited.ok()) {
    PrintError(command + " " + label + ": " + edited.status().message());
    return kExitFailed;
  }
  StatusOr<std::string> out =
      full ? voxel::WriteFullOctree(**edited) : voxel::WriteBinaryOctree(**edited);
  if (!out.ok()) {
    PrintError(command + ": " + out.status().message());
    return kExitFailed;
  }
  std::string error;
  if (!WriteOutput(output, *out, &error)) {
    PrintError(command + ": " + error);
    return kExitFailed;
  }
  const StatusOr<voxel::SubmapSummary> summary = voxel::InspectSubmap(*out);
  if (!summary.ok()) {  // our own output: a bug, but say so rather than guess
    PrintError(command + ": wrote " + output +
               ", which does not read back: " + summary.status().message());
    return kExitFailed;
  }
  std::printf("%s\n", Describe("wrote " + output, *out, *summary).c_str());
  return kExitOk;
}

int RunCrop(const Context& ctx, const CropOptions& flags) {
  if (flags.min_m.size() != 3 || flags.max_m.size() != 3) {
    return UsageError("submap crop", "--min and --max take X,Y,Z (three numbers each)");
  }
  const Eigen::AlignedBox3d box(Eigen::Vector3d(flags.min_m[0], flags.min_m[1], flags.min_m[2]),
                                Eigen::Vector3d(flags.max_m[0], flags.max_m[1], flags.max_m[2]));
  return RunEdit(ctx, "submap crop", flags.what, flags.output,
                 [&](const octomap::OcTree& tree) { return voxel::CropMap(tree, box); });
}

int RunTransform(const Context& ctx, const TransformOptions& flags) {
  if (flags.translate_m.size() != 3 || flags.rotate_deg.size() != 3) {
    return UsageError("submap transform", "--translate and --rotate take three numbers each");
  }
  constexpr double kRad = M_PI / 180.0;
  // p_out = R p_in + t, R = Rz(yaw) Ry(pitch) Rx(roll): the convention the
  // merge tables print (geometry::Rigid3::YawPitchRollDeg).
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(flags.rotate_deg[0] * kRad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(flags.rotate_deg[1] * kRad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(flags.rotate_deg[2] * kRad, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  // Whole quarter turns exactly: cos(90 deg) in doubles is 6e-17, not 0, and
  // the resampling would then drift across a voxel boundary over a long row.
  T.linear() = T.linear().unaryExpr([](double v) { return std::abs(v) < 1e-12 ? 0.0 : v; });
  T.translation() =
      Eigen::Vector3d(flags.translate_m[0], flags.translate_m[1], flags.translate_m[2]);
  return RunEdit(ctx, "submap transform", flags.what, flags.output,
                 [&](const octomap::OcTree& tree) { return voxel::TransformMap(tree, T); });
}

}  // namespace

void AddSubmapToolCommands(CLI::App* submap, Action* action) {
  CLI::App* info = submap->add_subcommand("info", "what an OctoMap file or a stored submap holds");
  info->footer(
      "Reads a local .bt/.ot file (no server needed) or a stored submap's bytes with the "
      "server's own validating reader: format, resolution, occupied and free voxels, the "
      "occupied bounds. A file that is not a usable OctoMap exits 1 naming why.");
  auto in = BindCommand(info, action, RunInfo);
  info->add_option("FILE|ID", in->what, "a file, or a submap id (see 'mapctl submaps')")
      ->required();

  CLI::App* crop = submap->add_subcommand(
      "crop", "cut a box out of an OctoMap file or a stored submap (-o OUT.bt|OUT.ot)");
  crop->footer(
      "Keeps the voxels whose centres lie in the box (metres, the map's own frame, faces "
      "included), occupied and free alike; everything outside becomes unknown. A .ot output "
      "keeps the log-odds. Exits 1 if no known voxel lies in the box (the message gives the "
      "map's bounds; 'mapctl submap info' too).");
  auto c = BindCommand(crop, action, RunCrop);
  crop->add_option("FILE|ID", c->what, "a file, or a submap id (see 'mapctl submaps')")->required();
  crop->add_option("--min", c->min_m, "X,Y,Z: the box's lowest corner, metres")
      ->required()
      ->delimiter(',')
      ->expected(3);
  crop->add_option("--max", c->max_m, "X,Y,Z: the box's highest corner, metres")
      ->required()
      ->delimiter(',')
      ->expected(3);
  crop->add_option("-o,--output", c->output, "the file to write (.bt or .ot)")->required();

  CLI::App* transform = submap->add_subcommand(
      "transform", "move an OctoMap file or a stored submap by a rigid transform (-o OUT)");
  transform->footer(
      "p_out = R p_in + t, R = Rz(yaw) Ry(pitch) Rx(roll) about the map frame's origin: the "
      "convention of 'mapctl merge show', so a merge's transform of a submap moves it into "
      "the reference frame. Resampled at the map's resolution (nearest voxel): occupied and "
      "free are kept, log-odds are not. Quarter turns with whole-voxel moves are exact.");
  auto t = BindCommand(transform, action, RunTransform);
  transform->add_option("FILE|ID", t->what, "a file, or a submap id (see 'mapctl submaps')")
      ->required();
  transform->add_option("--translate", t->translate_m, "X,Y,Z: t, metres")
      ->delimiter(',')
      ->expected(3)
      ->capture_default_str();
  transform->add_option("--rotate", t->rotate_deg, "YAW,PITCH,ROLL: R, degrees")
      ->delimiter(',')
      ->expected(3)
      ->capture_default_str();
  transform->add_option("-o,--output", t->output, "the file to write (.bt or .ot)")->required();
}

}  // namespace mapd::client
