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
#include <string>
#include <thread>
#include <vector>

#include "client/commands.h"
#include "client/robot/carmen_log.h"
#include "client/robot/observation_batch.h"
#include "client/robot/robot_client.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct ReplayOptions {
  std::vector<std::string> logs;
  std::string robot_id;  // empty: each log's file name
  std::string session;   // empty: replay-<UTC time>
  double rate = 0;       // 0: as fast as possible; 1: as recorded; N: N times as fast
  double max_range_m = 80;
  uint64_t every = 1;       // every Nth scan
  std::string export_path;  // write JSON lines instead of streaming; - for stdout
};

// One log's robot: its batches, made before anything is sent.
struct Recording {
  std::string path;
  std::string robot_id;
  std::vector<pb::ObservationBatch> batches;
  std::vector<double> stamps_s;
  std::size_t lines = 0;
  robot::IngestCounts counts;
  std::vector<robot::Rejection> rejections;
  grpc::Status status;
};

// The robot id a log's file name gives: its name without directories and
// .gz / .log, characters outside the id alphabet as '-'.
std::string RobotIdOf(const std::string& path) {
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

// Reads `path` and makes every batch: a bad file or scan is reported here,
// before anything is sent. kContinue, or the exit code.
int Record(const ReplayOptions& flags, const std::string& session, Recording* r) {
  auto scans = robot::ReadCarmenLaserLog(r->path);
  if (!scans.ok()) {
    PrintError("replay: " + scans.status().message());
    return scans.status().code() == StatusCode::kNotFound ? kExitFailed : kExitUsage;
  }
  if (scans->empty()) {
    PrintError("replay: " + r->path + " has no FLASER line (not a CARMEN laser log?)");
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
  robot::RobotClientOptions options;
  options.give_up_after = ctx.timeout();
  options.token = ctx.token;
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

int RunReplay(const Context& ctx, const ReplayOptions& flags) {
  const std::string session = flags.session.empty() ? "replay-" + UtcStampForName() : flags.session;
  std::vector<Recording> recordings(flags.logs.size());
  std::size_t total = 0, lines = 0;
  for (std::size_t i = 0; i < flags.logs.size(); ++i) {
    Recording& r = recordings[i];
    r.path = flags.logs[i];
    r.robot_id = flags.robot_id.empty()   ? RobotIdOf(r.path)
                 : flags.logs.size() == 1 ? flags.robot_id
                                          : flags.robot_id + "-" + std::to_string(i + 1);
    if (int rc = Record(flags, session, &r); rc != kContinue) return rc;
    total += r.batches.size();
    lines += r.lines;
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
      std::printf("replay: wrote %zu batches (%zu lines, session %s) to %s\n", total, lines,
                  session.c_str(), flags.export_path.c_str());
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
  std::printf("replay: %zu robot%s, %zu scans, %zu lines, session %s, %.1f s: %s\n",
              recordings.size(), recordings.size() == 1 ? "" : "s", total, lines, session.c_str(),
              seconds, Summary(counts).c_str());
  if (rc != kExitOk) return rc;
  return counts.rejected > 0 ? kExitFailed : kExitOk;
}

}  // namespace

void AddReplayCommand(CLI::App* app, Action* action) {
  CLI::App* replay =
      app->add_subcommand("replay", "stream recorded robots (CARMEN laser logs) into mapd");
  replay->footer(
      "Each LOG is one robot: a CARMEN laser log (plain or .gz; its ROBOTLASER1 lines, or FLASER\n"
      "corrected laser poses of the map frame). Every scan goes through the robot library\n"
      "as a robot would send it: split-and-merge lines in the laser frame\n"
      "(docs/robot-library.md), the pose, the scan's time; one Ingest stream per robot, all\n"
      "at once. Every log is read and every scan extracted before anything is sent: a bad\n"
      "file sends nothing. Robots are named by their file names (intel-corrected.log.gz:\n"
      "intel-corrected), or --robot-id. Re-running with the same --session is safe: stored\n"
      "batches are answered 'duplicate'. Exit 2 for a malformed log, 1 for one that cannot\n"
      "be read or for rejected batches.");
  auto r = BindCommand(replay, action, RunReplay);
  replay->add_option("LOG", r->logs, "CARMEN laser logs, one robot each")->required();
  replay->add_option("--robot-id", r->robot_id, "name the robots ID (one log) or ID-1..N");
  replay->add_option("--session", r->session,
                     "session id (default replay-<UTC time>, so re-runs add data)");
  replay
      ->add_option("--rate", r->rate,
                   "0: as fast as the server takes them; 1: as recorded; N: N times as fast")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  replay
      ->add_option("--max-range", r->max_range_m,
                   "readings at or beyond this many metres are no return (FLASER does not "
                   "say the laser's maximum)")
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
