// mapctl watch: the live change feed of the fused map (WatchFeatureMap),
// one line per change, resumed from the last complete map_version whenever
// the stream breaks.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

#include "client/commands.h"
#include "client/format.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct WatchOptions {
  std::string bbox;
  std::string kind = "any";
  std::string robot;
  uint64_t since = 0;
  bool json = false;
};

std::atomic<bool> g_interrupted{false};  // lock-free: set from the signal handler
static_assert(std::atomic<bool>::is_always_lock_free);

extern "C" void OnInterrupt(int /*signal*/) { g_interrupted.store(true); }

// The call in progress, cancelled from a helper thread when Ctrl-C arrives
// (a signal handler may not call into gRPC).
class CurrentCall {
 public:
  void Set(grpc::ClientContext* call) {
    std::lock_guard<std::mutex> lock(mu_);
    call_ = call;
    if (call_ != nullptr && g_interrupted.load()) call_->TryCancel();
  }
  void CancelIfInterrupted() {
    std::lock_guard<std::mutex> lock(mu_);
    if (call_ != nullptr && g_interrupted.load()) call_->TryCancel();
  }

 private:
  std::mutex mu_;
  grpc::ClientContext* call_ = nullptr;
};

// Waits `delay` unless interrupted first; false if interrupted.
bool Pause(std::chrono::milliseconds delay) {
  const auto end = std::chrono::steady_clock::now() + delay;
  while (std::chrono::steady_clock::now() < end) {
    if (g_interrupted.load()) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return !g_interrupted.load();
}

// Errors a reconnect cannot fix.
bool Permanent(grpc::StatusCode code) {
  return code == grpc::StatusCode::INVALID_ARGUMENT ||
         code == grpc::StatusCode::PERMISSION_DENIED || code == grpc::StatusCode::UNAUTHENTICATED ||
         code == grpc::StatusCode::UNIMPLEMENTED;
}

int RunWatch(const Context& ctx, const WatchOptions& flags) {
  pb::WatchFeatureMapRequest request;
  std::string error;
  if (!flags.bbox.empty() && !ParseBbox(flags.bbox, request.mutable_bbox(), &error)) {
    return UsageError("watch", error);
  }
  if (flags.kind == "line") request.set_kind(pb::FEATURE_KIND_LINE);
  if (flags.kind == "plane") request.set_kind(pb::FEATURE_KIND_PLANE);
  request.set_robot_id(flags.robot);

  std::signal(SIGINT, OnInterrupt);
  std::signal(SIGTERM, OnInterrupt);
  CurrentCall current;
  std::atomic<bool> done{false};
  std::thread canceller([&] {
    while (!done.load()) {
      current.CancelIfInterrupted();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  struct Join {
    std::atomic<bool>& done;
    std::thread& thread;
    ~Join() {
      done = true;
      thread.join();
    }
  } join{done, canceller};

  uint64_t version = flags.since;  // of the last message with more = false
  bool received = false;           // anything from this server yet
  auto backoff = std::chrono::milliseconds(500);
  for (;;) {
    request.set_since_map_version(version);
    std::unique_ptr<grpc::ClientContext> call = ctx.NewStreamContext();
    current.Set(call.get());
    std::unique_ptr<grpc::ClientReader<pb::FeatureMapDelta>> reader =
        ctx.stub->WatchFeatureMap(call.get(), request);
    pb::FeatureMapDelta delta;
    bool got = false;
    while (reader->Read(&delta)) {
      got = received = true;
      std::fputs(FormatDeltaLines(delta, flags.json).c_str(), stdout);
      std::fflush(stdout);
      if (!delta.more()) version = delta.map_version();
    }
    const grpc::Status status = reader->Finish();
    current.Set(nullptr);
    if (g_interrupted.load()) return kExitOk;  // Ctrl-C: a clean end
    if (got) backoff = std::chrono::milliseconds(500);
    if (Permanent(status.error_code())) {
      // A version the server does not know (its database was replaced):
      // start again from the full map, once.
      if (status.error_code() == grpc::StatusCode::INVALID_ARGUMENT && version > 0 &&
          status.error_message().find("since_map_version") != std::string::npos && received) {
        PrintError("watch: " + status.error_message() + "; starting again from the full map");
        version = 0;
        continue;
      }
      return ReportRpcError(ctx, "watch", status);
    }
    if (!received) return ReportRpcError(ctx, "watch", status);  // never connected
    std::fprintf(stderr,
                 "mapctl: watch: the stream ended (%s: %s); reconnecting in %.1f s from "
                 "map_version %llu\n",
                 StatusCodeName(status.error_code()), Visible(status.error_message()).c_str(),
                 static_cast<double>(backoff.count()) / 1000.0,
                 static_cast<unsigned long long>(version));
    if (!Pause(backoff)) return kExitOk;
    backoff = std::min(backoff * 2, std::chrono::milliseconds(10000));
  }
}

}  // namespace

void AddWatchCommand(CLI::App* app, Action* action) {
  CLI::App* watch = app->add_subcommand("watch", "print the fused map's changes live");
  watch->footer(
      "First the filtered map (a 'resync' line, then one 'added' line per feature), then one\n"
      "line per change as robots map: added, updated, removed (a feature leaving the filter,\n"
      "e.g. the bbox, is removed). When the stream breaks it reconnects with the last\n"
      "map_version (backoff 0.5 s to 10 s) and misses nothing; if the server no longer holds\n"
      "the changes since then, a resync line starts the full map again. Ctrl-C ends it (exit 0).");
  auto w = BindCommand(watch, action, RunWatch);
  watch->add_option("--bbox", w->bbox,
                    "XMIN,YMIN,XMAX,YMAX: only features whose segment meets this box, and "
                    "planes whose boundary's ground projection meets it");
  watch->add_option("--kind", w->kind, "only this kind (line leaves out the planes)")
      ->capture_default_str()
      ->check(CLI::IsMember({"line", "plane", "any"}));
  watch->add_option("--robot", w->robot, "only features this robot contributed to");
  watch
      ->add_option("--since", w->since,
                   "resume after this map_version (from an earlier watch or features --format "
                   "json); 0 = start with the full map")
      ->capture_default_str();
  watch->add_flag("--json", w->json,
                  "JSON lines: {\"map_version\", \"change\", \"type\", \"id\", \"feature\" | "
                  "\"plane\"}, snake_case");
}

}  // namespace mapd::client
