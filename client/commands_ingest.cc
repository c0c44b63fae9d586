// mapctl ingest | simulate
#include <google/protobuf/util/json_util.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <map>
#include <thread>

#include "client/commands.h"
#include "client/robot/robot_client.h"
#include "client/sim_robot.h"
#include "client/text_util.h"
#include "common/clock.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct IngestOptions {
  std::string path;  // - for stdin
};

struct SimulateOptions {
  uint64_t robots = 2;
  uint64_t scans = 100;
  uint64_t seed = 1;
  std::string session;  // empty: sim-<UTC time>
  std::string export_path;
  std::string robot_id;
  // A change of the world after some laps (SimRobotParams::change).
  std::vector<size_t> remove_walls;
  std::vector<std::string> add_walls;  // "x0,y0,x1,y1", metres
  double change_after_laps = 1.0;
};

// The world change the flags ask for, or an error naming the bad flag.
bool ParseWorldChange(const SimulateOptions& flags, bool* has_change, WorldChange* change,
                      std::string* error) {
  *has_change = !flags.remove_walls.empty() || !flags.add_walls.empty();
  change->after_laps = flags.change_after_laps;
  const size_t walls = DefaultWorld().walls.size();
  for (size_t index : flags.remove_walls) {
    if (index >= walls) {
      *error = Printf("simulate: --remove-wall %zu: the floor has walls 0..%zu (see --help)", index,
                      walls - 1);
      return false;
    }
    change->remove.push_back(index);
  }
  for (const std::string& text : flags.add_walls) {
    double v[4];
    char tail = 0;
    if (std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &tail) != 4 ||
        !std::isfinite(v[0] + v[1] + v[2] + v[3]) || (v[0] == v[2] && v[1] == v[3])) {
      *error = "simulate: --add-wall '" + text +
               "' is not X0,Y0,X1,Y1 (metres, map frame, two different points)";
      return false;
    }
    change->add.push_back({Vec2(v[0], v[1]), Vec2(v[2], v[3])});
  }
  return true;
}

double WorldLoopLengthM() {
  const SimWorld world = DefaultWorld();
  double length = 0.0;
  for (size_t i = 0; i < world.loop.size(); ++i) {
    length += (world.loop[(i + 1) % world.loop.size()] - world.loop[i]).norm();
  }
  return length;
}

std::string WallList() {
  std::string text;
  const SimWorld world = DefaultWorld();
  for (size_t i = 0; i < world.walls.size(); ++i) {
    const Segment2& w = world.walls[i];
    text += Printf("  %2zu  %g,%g,%g,%g\n", i, w.a.x(), w.a.y(), w.b.x(), w.b.y());
  }
  return text;
}

struct Tally {
  robot::IngestCounts counts;
  std::vector<robot::Rejection> rejections;
  grpc::Status status;
};

int RunIngest(const Context& ctx, const IngestOptions& flags) {
  const std::string& path = flags.path;
  std::ifstream file;
  if (path != "-") {
    file.open(path);
    if (!file) {
      PrintError("ingest: cannot open " + path);
      return kExitFailed;
    }
  }
  std::istream& in = path == "-" ? std::cin : file;
  if (int rc = CheckReachable(ctx, "ingest"); rc != kExitOk) return rc;

  const robot::RobotClientOptions options = ctx.RobotOptions();  // settles ctx.channel
  robot::RobotClient client(ctx.channel, options);
  std::map<std::pair<std::string, uint64_t>, size_t> line_of;  // (session, seq) -> line number
  std::string line, parse_error;
  size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    pb::ObservationBatch batch;
    const auto parsed = google::protobuf::util::JsonStringToMessage(line, &batch);
    if (!parsed.ok()) {
      std::string why(parsed.message());
      why = why.substr(0, why.find('\n'));  // the parser adds the line and a caret below
      parse_error = Printf("ingest: %s line %zu is not an ObservationBatch in protobuf JSON: %s",
                           path.c_str(), line_number, why.c_str());
      break;
    }
    line_of.emplace(std::make_pair(batch.session_id(), batch.seq()), line_number);
    client.Send(std::move(batch));
  }
  const grpc::Status status = client.Finish(ctx.timeout());
  const robot::IngestCounts counts = client.counts();
  std::printf("ingest: %s\n", Summary(counts).c_str());
  for (const robot::Rejection& r : client.rejections()) {
    const auto it = line_of.find({r.session_id, r.seq});
    const std::string where = it == line_of.end() ? "a batch" : Printf("line %zu", it->second);
    std::fprintf(stderr, "mapctl: ingest: %s (session %s, seq %llu) rejected: %s (%s)\n",
                 where.c_str(), Visible(r.session_id).c_str(),
                 static_cast<unsigned long long>(r.seq), Visible(r.message).c_str(),
                 StatusCodeName(r.code));
  }
  if (!parse_error.empty()) {
    PrintError(parse_error);
    return kExitUsage;
  }
  if (!status.ok()) return ReportRpcError(ctx, "ingest", status);
  return counts.rejected > 0 ? kExitFailed : kExitOk;
}

int RunSimulate(const Context& ctx, const SimulateOptions& flags) {
  const uint64_t robots = flags.robots, scans = flags.scans, seed = flags.seed;
  const std::string session = flags.session.empty() ? "sim-" + UtcStampForName() : flags.session;

  bool has_change = false;
  WorldChange change;
  if (std::string error; !ParseWorldChange(flags, &has_change, &change, &error)) {
    PrintError(error);
    return kExitUsage;
  }
  const int64_t start_ns = UnixNowNs();
  std::vector<SimRobotParams> params(robots);
  for (size_t i = 0; i < robots; ++i) {
    const std::string& base = flags.robot_id;
    params[i].robot_id = base.empty()  ? "sim-robot-" + std::to_string(i + 1)
                         : robots == 1 ? base
                                       : base + "-" + std::to_string(i + 1);
    params[i].session_id = session;
    params[i].seed = seed * 1000003 + i;
    params[i].start_fraction = static_cast<double>(i) / static_cast<double>(robots);
    params[i].start_stamp_ns = start_ns;
    params[i].has_change = has_change;
    params[i].change = change;
  }

  if (!flags.export_path.empty()) {
    std::vector<SimRobot> sims;
    for (const SimRobotParams& p : params) sims.emplace_back(DefaultWorld(), p);
    std::string text, json;
    for (uint64_t s = 0; s < scans; ++s) {
      for (SimRobot& sim : sims) {
        json.clear();
        // The .proto field names (snake_case), as `status --json` writes them.
        google::protobuf::util::JsonPrintOptions options;
        options.preserve_proto_field_names = true;
        (void)google::protobuf::util::MessageToJsonString(sim.NextBatch(), &json, options);
        text += json + "\n";
      }
    }
    std::string error;
    if (!WriteOutput(flags.export_path, text, &error)) {
      PrintError("simulate: " + error);
      return kExitFailed;
    }
    if (flags.export_path != "-") {
      std::printf("simulate: wrote %llu batches (%llu robots x %llu scans, session %s) to %s\n",
                  static_cast<unsigned long long>(robots * scans),
                  static_cast<unsigned long long>(robots), static_cast<unsigned long long>(scans),
                  session.c_str(), flags.export_path.c_str());
    }
    return kExitOk;
  }

  if (int rc = CheckReachable(ctx, "simulate"); rc != kExitOk) return rc;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Tally> tallies(robots);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < robots; ++i) {
    threads.emplace_back([&ctx, &params, &tallies, scans, i] {
      SimRobot sim(DefaultWorld(), params[i]);
      const robot::RobotClientOptions options = ctx.RobotOptions();  // settles ctx.channel
      robot::RobotClient client(ctx.channel, options);
      for (uint64_t s = 0; s < scans; ++s) client.Send(sim.NextBatch());
      tallies[i].status = client.Finish(ctx.timeout());
      tallies[i].counts = client.counts();
      tallies[i].rejections = client.rejections();
    });
  }
  for (std::thread& t : threads) t.join();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  robot::IngestCounts total;
  int rc = kExitOk;
  for (size_t i = 0; i < robots; ++i) {
    Add(tallies[i].counts, &total);
    for (const robot::Rejection& r : tallies[i].rejections) {
      std::fprintf(stderr, "mapctl: simulate: %s seq %llu rejected: %s (%s)\n",
                   params[i].robot_id.c_str(), static_cast<unsigned long long>(r.seq),
                   Visible(r.message).c_str(), StatusCodeName(r.code));
    }
    if (!tallies[i].status.ok() && rc == kExitOk) {
      rc = ReportRpcError(ctx, "simulate " + params[i].robot_id, tallies[i].status);
    }
  }
  std::printf("simulate: %llu robots x %llu scans, session %s, %.1f s: %s\n",
              static_cast<unsigned long long>(robots), static_cast<unsigned long long>(scans),
              session.c_str(), seconds, Summary(total).c_str());
  if (has_change) {
    const double laps = static_cast<double>(scans) * SimRobotParams().step_m / WorldLoopLengthM();
    std::printf(
        "simulate: the floor changed after %g of each robot's %.1f laps "
        "(%zu walls removed, %zu added)\n",
        change.after_laps, laps, change.remove.size(), change.add.size());
  }
  if (rc != kExitOk) return rc;
  return total.rejected > 0 ? kExitFailed : kExitOk;
}

}  // namespace

void Add(const robot::IngestCounts& c, robot::IngestCounts* total) {
  total->sent += c.sent;
  total->stored += c.stored;
  total->duplicate += c.duplicate;
  total->rejected += c.rejected;
  total->reconnects += c.reconnects;
}

std::string Summary(const robot::IngestCounts& c) {
  return Printf("%llu batches sent: %llu stored, %llu duplicate, %llu rejected",
                static_cast<unsigned long long>(c.sent), static_cast<unsigned long long>(c.stored),
                static_cast<unsigned long long>(c.duplicate),
                static_cast<unsigned long long>(c.rejected)) +
         (c.reconnects > 0
              ? Printf(" (%llu reconnects)", static_cast<unsigned long long>(c.reconnects))
              : "");
}

std::string UtcStampForName() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char out[32];
  std::strftime(out, sizeof(out), "%Y%m%dT%H%M%SZ", &tm);
  return out;
}

void AddIngestCommands(CLI::App* app, Action* action) {
  CLI::App* ingest =
      app->add_subcommand("ingest", "stream observation batches from a JSON-lines file");
  ingest->footer(
      "Streams observation batches to the server over one Ingest stream. FILE (or - for\n"
      "stdin) holds JSON lines: one ObservationBatch per line in the protobuf JSON mapping\n"
      "(.proto or camelCase field names); empty lines and lines starting with # are skipped.\n"
      "Batches are pipelined; the ones not acknowledged are resent after a dropped\n"
      "connection. Re-running a file is safe: batches stored before are answered 'duplicate'.\n"
      "Prints stored / duplicate / rejected counts and each rejection with its line number.\n"
      "Exit 1 if any batch was rejected; 2 if a line is not an ObservationBatch (the lines\n"
      "before it are sent).");
  ingest
      ->add_option("FILE", BindCommand(ingest, action, RunIngest)->path, "JSON lines, - for stdin")
      ->required();

  CLI::App* simulate =
      app->add_subcommand("simulate", "stream (or export) simulated robots' laser lines");
  simulate->footer(
      "Simulated robots drive a loop through a 20 m x 12 m floor, scan it with a 2D laser\n"
      "(180 beams, 10 m, 1 cm noise), extract wall segments and stream them, one Ingest\n"
      "stream per robot, concurrently. Deterministic for a seed. A loop is 36 m, 180 scans.\n"
      "\n"
      "Buildings change: --remove-wall and --add-wall change the floor once each robot has\n"
      "driven --change-after-laps loops; mapd retires a wall the robots then see through\n"
      "(fusion.retire_views) and publishes one that appears. The floor's walls, x0,y0,x1,y1:\n" +
      WallList());
  auto s = BindCommand(simulate, action, RunSimulate);
  simulate->add_option("--robots", s->robots, "number of robots, named sim-robot-1..N")
      ->capture_default_str()
      ->check(CLI::Range(uint64_t{1}, uint64_t{1000}));
  simulate->add_option(
      "--robot-id", s->robot_id,
      "name the robots ID (one robot) or ID-1..N; a robot token (--token) may write only its "
      "own robot id");
  simulate->add_option("--scans", s->scans, "scans per robot, 0.2 m apart")
      ->capture_default_str()
      ->check(CLI::Range(uint64_t{0}, uint64_t{10000000}));
  simulate->add_option("--seed", s->seed, "random seed")->capture_default_str();
  simulate->add_option("--session", s->session,
                       "session id (default sim-<UTC time>, so re-runs add data)");
  simulate->add_option("--remove-wall", s->remove_walls,
                       "index of a wall (listed below) that is gone after the change; repeatable");
  simulate->add_option("--add-wall", s->add_walls,
                       "X0,Y0,X1,Y1: a wall that stands after the change (metres); repeatable");
  simulate
      ->add_option("--change-after-laps", s->change_after_laps,
                   "loops each robot drives before the change")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  simulate->add_option(
      "--export", s->export_path,
      "write the batches as JSON lines (for 'mapctl ingest') instead of streaming them; - for "
      "stdout");
}

}  // namespace mapd::client
