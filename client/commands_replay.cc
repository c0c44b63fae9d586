// mapctl replay: recorded robots streamed into mapd through the robot library,
// as the robots would have streamed them (client/robot: ExtractLines,
// ScanBatch, RobotClient).
#include <google/protobuf/util/json_util.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "client/commands.h"
#include "client/replay.h"
#include "client/robot/carmen_log.h"
#include "client/robot/observation_batch.h"
#include "client/robot/robot_client.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

// The robot id a source's name gives: its name without directories and
// .gz / .log, characters outside the id alphabet as '-'.
std::string RobotIdOf(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();  // a folder
  std::string name = path.substr(path.find_last_of('/') + 1);
  for (const char* suffix : {".gz", ".log"}) {
    const std::string s = suffix;
    if (name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0) {
      name.resize(name.size() - s.size());
    }
  }
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '.' && c != '-') c = '-';
  }
  if (name.size() > 128) name.resize(128);
  return name.empty() ? "replay-robot" : name;
}

// Reads the CARMEN log r->path and makes every batch: a bad file or scan is
// reported here, before anything is sent. kContinue, or the exit code.
int RecordLog(const ReplayOptions& flags, const std::string& session, Recording* r) {
  auto scans = robot::ReadCarmenLaserLog(r->path);
  if (!scans.ok()) {
    PrintError("replay: " + scans.status().message());
    return scans.status().code() == StatusCode::kNotFound ? kExitFailed : kExitUsage;
  }
  if (scans->empty()) {
    PrintError("replay: " + r->path +
               " has no FLASER or ROBOTLASER1 line (not a CARMEN laser log?)");
    return kExitUsage;
  }
  const robot::LineExtractionParams params;
  for (std::size_t i = 0; i < scans->size(); i += flags.every) {
    const robot::CarmenScan& scan = (*scans)[i];
    robot::BatchHeader header;
    header.robot_id = r->robot_id;
    header.session_id = session;
    header.seq = r->batches.size() + 1;
    header.stamp_ns = static_cast<int64_t>(std::llround(scan.timestamp_s * 1e9));
    Eigen::Isometry3d T_map_laser = Eigen::Isometry3d::Identity();
    T_map_laser.linear() =
        Eigen::AngleAxisd(scan.theta_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T_map_laser.translation() = Eigen::Vector3d(scan.x_m, scan.y_m, 0);
    auto batch =
        robot::ScanBatch(header, T_map_laser, robot::ToLaserScan(scan, flags.max_range_m), params);
    if (!batch.ok()) {
      PrintError(Printf("replay: %s, scan %zu: %s", r->path.c_str(), i + 1,
                        batch.status().message().c_str()));
      return kExitUsage;
    }
    r->lines += static_cast<std::size_t>(batch->lines_size());
    r->stamps_s.push_back(scan.timestamp_s);
    r->batches.push_back(std::move(batch).value());
  }
  return kContinue;
}

// Streams one recording; `sent` counts its batches for the progress line.
void Stream(const Context& ctx, const ReplayOptions& flags,
            std::chrono::steady_clock::time_point t0, Recording* r,
            std::atomic<std::size_t>* sent) {
  const robot::RobotClientOptions options = ctx.RobotOptions();  // settles ctx.channel
  robot::RobotClient client(ctx.channel, options);
  for (std::size_t i = 0; i < r->batches.size(); ++i) {
    if (flags.rate > 0) {  // as recorded, or N times as fast
      const double at_s = (r->stamps_s[i] - r->stamps_s.front()) / flags.rate;
      std::this_thread::sleep_until(t0 + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                             std::chrono::duration<double>(std::max(at_s, 0.0))));
    }
    client.Send(std::move(r->batches[i]));
    ++*sent;
  }
  r->status = client.Finish(ctx.timeout());
  r->counts = client.counts();
  r->rejections = client.rejections();
}

// Makes every recording: a log, or a folder of scans with the next --poses
// file (or its own poses.txt).
int RecordAll(const ReplayOptions& flags, const std::string& session,
              std::vector<Recording>* recordings) {
  std::error_code ec;
  const std::size_t folder_count = static_cast<std::size_t>(
      std::count_if(flags.sources.begin(), flags.sources.end(),
                    [&ec](const std::string& s) { return std::filesystem::is_directory(s, ec); }));
  if (folder_count < flags.poses.size()) {  // before reading anything
    PrintError(
        Printf("replay: %zu --poses files for %zu scan folders", flags.poses.size(), folder_count));
    return kExitUsage;
  }
  std::size_t folders = 0;
  for (std::size_t i = 0; i < flags.sources.size(); ++i) {
    Recording& r = (*recordings)[i];
    r.path = flags.sources[i];
    r.robot_id = flags.robot_id.empty()      ? RobotIdOf(r.path)
                 : flags.sources.size() == 1 ? flags.robot_id
                                             : flags.robot_id + "-" + std::to_string(i + 1);
    if (!std::filesystem::is_directory(r.path, ec)) {
      if (int rc = RecordLog(flags, session, &r); rc != kContinue) return rc;
      continue;
    }
    std::string poses = folders < flags.poses.size() ? flags.poses[folders] : "";
    ++folders;
    if (poses.empty()) {
      poses = r.path + "/poses.txt";
      if (!std::filesystem::is_regular_file(poses, ec)) {
        PrintError("replay: the scan folder " + r.path +
                   " needs its poses: --poses FILE (TUM or KITTI), or a poses.txt in it");
        return kExitUsage;
      }
    }
    if (int rc = RecordCloudFolder(flags, session, poses, &r); rc != kContinue) return rc;
  }
  return kContinue;
}

// "N lines", "M planes" or both.
std::string FeatureCounts(std::size_t lines, std::size_t planes) {
  std::string out;
  if (lines > 0 || planes == 0) out = Printf("%zu lines", lines);
  if (planes > 0) out += (out.empty() ? "" : ", ") + Printf("%zu planes", planes);
  return out;
}

int RunReplay(const Context& ctx, const ReplayOptions& flags) {
  const std::string session = flags.session.empty() ? "replay-" + UtcStampForName() : flags.session;
  std::vector<Recording> recordings(flags.sources.size());
  if (int rc = RecordAll(flags, session, &recordings); rc != kContinue) return rc;
  std::size_t total = 0, lines = 0, planes = 0;
  for (const Recording& r : recordings) {
    total += r.batches.size();
    lines += r.lines;
    planes += r.planes;
    if (r.skipped > 0) {
      std::fprintf(stderr, "mapctl: replay: %s: %zu scans without a pose within %.3f s, skipped\n",
                   r.path.c_str(), r.skipped, flags.max_dt_s);
    }
  }
  for (std::size_t i = 0; i < recordings.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (recordings[i].robot_id == recordings[j].robot_id) {
        PrintError("replay: " + recordings[j].path + " and " + recordings[i].path +
                   " would both be robot " + recordings[i].robot_id +
                   "; name them with --robot-id");
        return kExitUsage;
      }
    }
  }
  if (!flags.export_path.empty()) {
    // The .proto field names (snake_case), as `simulate --export` writes them.
    google::protobuf::util::JsonPrintOptions options;
    options.preserve_proto_field_names = true;
    std::string text, json;
    for (const Recording& r : recordings) {
      for (const pb::ObservationBatch& batch : r.batches) {
        json.clear();
        (void)google::protobuf::util::MessageToJsonString(batch, &json, options);
        text += json + "\n";
      }
    }
    std::string error;
    if (!WriteOutput(flags.export_path, text, &error)) {
      PrintError("replay: " + error);
      return kExitFailed;
    }
    if (flags.export_path != "-") {
      std::printf("replay: wrote %zu batches (%s, session %s) to %s\n", total,
                  FeatureCounts(lines, planes).c_str(), session.c_str(), flags.export_path.c_str());
    }
    return kExitOk;
  }
  if (int rc = CheckReachable(ctx, "replay"); rc != kExitOk) return rc;

  const auto t0 = std::chrono::steady_clock::now();
  std::atomic<std::size_t> sent{0};
  std::vector<std::thread> threads;
  for (Recording& r : recordings) {
    threads.emplace_back([&ctx, &flags, t0, &r, &sent] { Stream(ctx, flags, t0, &r, &sent); });
  }
  // The progress bar, on a terminal: streaming a long log as recorded takes
  // as long as the robot drove.
  const bool tty = isatty(STDERR_FILENO) != 0;
  for (;;) {
    const std::size_t done = sent.load();
    if (tty) {
      constexpr int kWidth = 30;
      const int filled = total == 0 ? kWidth : static_cast<int>(kWidth * done / total);
      std::fprintf(stderr, "\rreplay: [%s%s] %zu / %zu scans", std::string(filled, '#').c_str(),
                   std::string(kWidth - filled, ' ').c_str(), done, total);
      std::fflush(stderr);
    }
    if (done >= total) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  if (tty) std::fprintf(stderr, "\n");
  for (std::thread& t : threads) t.join();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  robot::IngestCounts counts;
  int rc = kExitOk;
  for (const Recording& r : recordings) {
    Add(r.counts, &counts);
    for (const robot::Rejection& x : r.rejections) {
      std::fprintf(stderr, "mapctl: replay: %s seq %llu rejected: %s (%s)\n", r.robot_id.c_str(),
                   static_cast<unsigned long long>(x.seq), Visible(x.message).c_str(),
                   StatusCodeName(x.code));
    }
    if (!r.status.ok() && rc == kExitOk) rc = ReportRpcError(ctx, "replay " + r.robot_id, r.status);
  }
  std::printf("replay: %zu robot%s, %zu scans, %s, session %s, %.1f s: %s\n", recordings.size(),
              recordings.size() == 1 ? "" : "s", total, FeatureCounts(lines, planes).c_str(),
              session.c_str(), seconds, Summary(counts).c_str());
  if (rc != kExitOk) return rc;
  return counts.rejected > 0 ? kExitFailed : kExitOk;
}

}  // namespace

void AddReplayCommand(CLI::App* app, Action* action) {
  CLI::App* replay = app->add_subcommand(
      "replay", "stream recorded robots (CARMEN laser logs, folders of 3D scans) into mapd");
  replay->footer(
      "Each SOURCE is one robot, streamed through the robot library as the robot would\n"
      "have sent it (docs/robot-library.md):\n"
      "  a CARMEN laser log (plain or .gz): its ROBOTLASER1 lines, or FLASER, with the\n"
      "    corrected laser poses of the map frame; split-and-merge lines per scan;\n"
      "  a folder of 3D scans (.pcd, .ply, KITTI .bin, .xyz; planes by libmapd_robot_c.so,\n"
      "    loaded from $MAPD_ROBOT_LIBRARY, ../lib beside mapctl or the library path):\n"
      "    RANSAC planes per scan, posed by a trajectory: --poses FILE (one per folder, in\n"
      "    order; default FOLDER/poses.txt), TUM (t x y z qx qy qz qw, z up) or KITTI (3 x 4\n"
      "    matrices by order, with times.txt and calib.txt's Tr when beside the folder,\n"
      "    turned to z up). TUM poses go with scans named by their times (nearest within\n"
      "    --max-dt), or else (other names, numbers that are no pose's time) by order.\n"
      "One Ingest stream per robot, all at once. Every source is read and every scan\n"
      "extracted before anything is sent: a bad file sends nothing. Robots are named by\n"
      "their file or folder names (intel-corrected.log.gz: intel-corrected), or --robot-id.\n"
      "Re-running with the same --session is safe: stored batches are answered 'duplicate'.\n"
      "Exit 2 for a malformed file, 1 for one that cannot be read or for rejected batches.");
  auto r = BindCommand(replay, action, RunReplay);
  replay->add_option("SOURCE", r->sources, "CARMEN laser logs and 3D scan folders, one robot each")
      ->required();
  replay
      ->add_option("--poses", r->poses,
                   "a scan folder's trajectory (TUM or KITTI); repeat for each folder")
      ->allow_extra_args(false);
  replay->add_option("--poses-format", r->poses_format, "auto (by count of numbers), tum or kitti")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "tum", "kitti"}));
  replay
      ->add_option("--max-dt", r->max_dt_s,
                   "TUM: the largest time between a scan and its pose, seconds")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 10.0));
  replay->add_flag("--wrap-columns", r->wrap_columns,
                   "organised scans come from a 360 degree LiDAR: their last column touches "
                   "the first");
  replay->add_option("--robot-id", r->robot_id, "name the robots ID (one source) or ID-1..N");
  replay->add_option("--session", r->session,
                     "session id (default replay-<UTC time>, so re-runs add data)");
  replay
      ->add_option("--rate", r->rate,
                   "0: as fast as the server takes them; 1: as recorded; N: N times as fast")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  replay
      ->add_option("--max-range", r->max_range_m,
                   "laser readings at or beyond this many metres are no return (FLASER does "
                   "not say the laser's maximum)")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  replay->add_option(
      "--export", r->export_path,
      "write the batches as JSON lines (for 'mapctl ingest') instead of streaming them; - for "
      "stdout");
  replay->add_option("--every", r->every, "send every Nth scan")
      ->capture_default_str()
      ->check(CLI::Range(uint64_t{1}, uint64_t{1000000}));
}

}  // namespace mapd::client
