// mapctl ingest | simulate
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <map>
#include <thread>

#include <google/protobuf/util/json_util.h>

#include "client/commands.h"
#include "client/robot_client.h"
#include "client/sim_robot.h"
#include "client/text_util.h"
#include "common/clock.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

const char kIngestHelp[] =
    "Usage: mapctl ingest FILE\n"
    "Streams observation batches to the server over one Ingest stream. FILE (or - for\n"
    "stdin) holds JSON lines: one ObservationBatch per line in the protobuf JSON mapping;\n"
    "empty lines and lines starting with # are skipped. Batches are pipelined; the ones\n"
    "not acknowledged are resent after a dropped connection. Re-running a file is safe:\n"
    "batches stored before are answered 'duplicate'.\n"
    "Prints stored / duplicate / rejected counts and each rejection with its line number.\n"
    "Exit 1 if any batch was rejected; 2 if a line is not an ObservationBatch (the lines\n"
    "before it are sent).\n";

const char kSimulateHelp[] =
    "Usage: mapctl simulate [options]\n"
    "Simulated robots drive a loop through a 20 m x 12 m floor, scan it with a 2D laser\n"
    "(180 beams, 10 m, 1 cm noise), extract wall segments and stream them, one Ingest\n"
    "stream per robot, concurrently. Deterministic for a seed.\n"
    "  --robots N        number of robots (default 2), named sim-robot-1..N\n"
    "  --robot-id ID     name the robots ID (one robot) or ID-1..N; a robot token\n"
    "                    (--token) may write only its own robot id\n"
    "  --scans N         scans per robot (default 100), 0.2 m apart\n"
    "  --seed S          random seed (default 1)\n"
    "  --session NAME    session id (default sim-<UTC time>, so re-runs add data)\n"
    "  --export FILE     write the batches as JSON lines (for 'mapctl ingest') instead\n"
    "                    of streaming them; - for stdout\n";

struct Tally {
  IngestCounts counts;
  std::vector<Rejection> rejections;
  grpc::Status status;
};

void Add(const IngestCounts& c, IngestCounts* total) {
  total->sent += c.sent;
  total->stored += c.stored;
  total->duplicate += c.duplicate;
  total->rejected += c.rejected;
  total->reconnects += c.reconnects;
}

std::string Summary(const IngestCounts& c) {
  return Printf("%llu batches sent: %llu stored, %llu duplicate, %llu rejected",
                static_cast<unsigned long long>(c.sent), static_cast<unsigned long long>(c.stored),
                static_cast<unsigned long long>(c.duplicate), static_cast<unsigned long long>(c.rejected)) +
         (c.reconnects > 0 ? Printf(" (%llu reconnects)", static_cast<unsigned long long>(c.reconnects)) : "");
}

std::string UtcStampForName() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char out[32];
  std::strftime(out, sizeof(out), "%Y%m%dT%H%M%SZ", &tm);
  return out;
}

}  // namespace

int RunIngest(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("ingest", kIngestHelp, args, {}, &flags); rc != kContinue) return rc;
  if (flags.positionals().size() != 1) return UsageError("ingest", "wants exactly one FILE (or - for stdin)");
  const std::string path = flags.positionals()[0];
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

  RobotClientOptions options;
  options.give_up_after = ctx.timeout();
  options.token = ctx.token;
  RobotClient client(ctx.channel, options);
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
      parse_error = Printf("ingest: %s line %zu is not an ObservationBatch in protobuf JSON: %s", path.c_str(),
                           line_number, why.c_str());
      break;
    }
    line_of.emplace(std::make_pair(batch.session_id(), batch.seq()), line_number);
    client.Send(std::move(batch));
  }
  const grpc::Status status = client.Finish(ctx.timeout());
  const IngestCounts counts = client.counts();
  std::printf("ingest: %s\n", Summary(counts).c_str());
  for (const Rejection& r : client.rejections()) {
    const auto it = line_of.find({r.session_id, r.seq});
    const std::string where = it == line_of.end() ? "a batch" : Printf("line %zu", it->second);
    std::fprintf(stderr, "mapctl: ingest: %s (session %s, seq %llu) rejected: %s (%s)\n", where.c_str(),
                 r.session_id.c_str(), static_cast<unsigned long long>(r.seq), r.message.c_str(),
                 StatusCodeName(r.code));
  }
  if (!parse_error.empty()) {
    PrintError(parse_error);
    return kExitUsage;
  }
  if (!status.ok()) return ReportRpcError(ctx, "ingest", status);
  return counts.rejected > 0 ? kExitFailed : kExitOk;
}

int RunSimulate(const Context& ctx, const CommandArgs& args) {
  Args flags;
  const std::vector<FlagSpec> specs = {
      {"--robots", true}, {"--scans", true}, {"--seed", true}, {"--session", true}, {"--export", true},
      {"--robot-id", true}};
  if (int rc = ParseCommandArgs("simulate", kSimulateHelp, args, specs, &flags); rc != kContinue) return rc;
  if (!flags.positionals().empty()) {
    return UsageError("simulate", "unexpected argument '" + flags.positionals()[0] + "'");
  }
  uint64_t robots = 0, scans = 0, seed = 0;
  if (!ParseUint(flags.Get("--robots", "2"), &robots) || robots < 1 || robots > 1000) {
    return UsageError("simulate", "--robots wants 1..1000, got '" + flags.Get("--robots") + "'");
  }
  if (!ParseUint(flags.Get("--scans", "100"), &scans) || scans > 10000000) {
    return UsageError("simulate", "--scans wants a count, got '" + flags.Get("--scans") + "'");
  }
  if (!ParseUint(flags.Get("--seed", "1"), &seed)) {
    return UsageError("simulate", "--seed wants a non-negative integer, got '" + flags.Get("--seed") + "'");
  }
  const std::string session = flags.Get("--session", "sim-" + UtcStampForName());

  const int64_t start_ns = UnixNowNs();
  std::vector<SimRobotParams> params(robots);
  for (size_t i = 0; i < robots; ++i) {
    const std::string base = flags.Get("--robot-id");
    params[i].robot_id = base.empty() ? "sim-robot-" + std::to_string(i + 1)
                         : robots == 1 ? base
                                       : base + "-" + std::to_string(i + 1);
    params[i].session_id = session;
    params[i].seed = seed * 1000003 + i;
    params[i].start_fraction = static_cast<double>(i) / static_cast<double>(robots);
    params[i].start_stamp_ns = start_ns;
  }

  if (flags.Has("--export")) {
    std::vector<SimRobot> sims;
    for (const SimRobotParams& p : params) sims.emplace_back(DefaultWorld(), p);
    std::string text, json;
    for (uint64_t s = 0; s < scans; ++s) {
      for (SimRobot& sim : sims) {
        json.clear();
        (void)google::protobuf::util::MessageToJsonString(sim.NextBatch(), &json);
        text += json + "\n";
      }
    }
    std::string error;
    if (!WriteOutput(flags.Get("--export"), text, &error)) {
      PrintError("simulate: " + error);
      return kExitFailed;
    }
    if (flags.Get("--export") != "-") {
      std::printf("simulate: wrote %llu batches (%llu robots x %llu scans, session %s) to %s\n",
                  static_cast<unsigned long long>(robots * scans), static_cast<unsigned long long>(robots),
                  static_cast<unsigned long long>(scans), session.c_str(), flags.Get("--export").c_str());
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
      RobotClientOptions options;
      options.give_up_after = ctx.timeout();
      options.token = ctx.token;
      RobotClient client(ctx.channel, options);
      for (uint64_t s = 0; s < scans; ++s) client.Send(sim.NextBatch());
      tallies[i].status = client.Finish(ctx.timeout());
      tallies[i].counts = client.counts();
      tallies[i].rejections = client.rejections();
    });
  }
  for (std::thread& t : threads) t.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  IngestCounts total;
  int rc = kExitOk;
  for (size_t i = 0; i < robots; ++i) {
    Add(tallies[i].counts, &total);
    for (const Rejection& r : tallies[i].rejections) {
      std::fprintf(stderr, "mapctl: simulate: %s seq %llu rejected: %s (%s)\n", params[i].robot_id.c_str(),
                   static_cast<unsigned long long>(r.seq), r.message.c_str(), StatusCodeName(r.code));
    }
    if (!tallies[i].status.ok() && rc == kExitOk) {
      rc = ReportRpcError(ctx, "simulate " + params[i].robot_id, tallies[i].status);
    }
  }
  std::printf("simulate: %llu robots x %llu scans, session %s, %.1f s: %s\n",
              static_cast<unsigned long long>(robots), static_cast<unsigned long long>(scans), session.c_str(),
              seconds, Summary(total).c_str());
  if (rc != kExitOk) return rc;
  return total.rejected > 0 ? kExitFailed : kExitOk;
}

}  // namespace mapd::client
