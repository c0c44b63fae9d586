// GET /api/events: the change feed as server-sent events. The same
// WatchHub as WatchFeatureMap (per-watcher bounded queue, history for
// resume), without filters:
//   event: resync   data: {"map_version", "features", "planes"}   the whole map;
//                   the page replaces what it holds
//   event: change   data: {"from_version", "map_version", "features", "removed",
//                   "planes", "removed_planes"}   features are upserts
// Each event's id is its map_version; a reconnecting EventSource sends it as
// Last-Event-ID (or ?since=V) and gets the changes after it, or a resync
// when the history no longer covers it (or it is newer than the map: another
// database). Comments (": ping") every 10 s find clients that went away.
#include <chrono>
#include <memory>

#include "service/log.h"
#include "service/watch_hub.h"
#include "web/http_util.h"
#include "web/web_json.h"

namespace mapd::web {
namespace {

constexpr std::chrono::milliseconds kPoll(250);  // how soon a stream sees Stop()
constexpr std::chrono::seconds kPing(10);

struct EventStream {
  std::shared_ptr<service::Core> core;  // held while the stream is open
  std::shared_ptr<service::Watcher> watcher;
  std::vector<service::ChangePtr> replay;  // sent first, then the queue
  bool resync = true;
  uint64_t version = 0;  // the client has the map at this version
  std::chrono::steady_clock::time_point last_write = std::chrono::steady_clock::now();

  ~EventStream() {
    if (watcher) core->watch_hub().Unsubscribe(watcher);
  }

  static bool Write(httplib::DataSink& sink, const std::string& text) {
    return sink.write(text.data(), text.size());
  }
  bool Event(httplib::DataSink& sink, const char* type, uint64_t id, const Json& data) {
    last_write = std::chrono::steady_clock::now();
    return Write(
        sink, "id: " + std::to_string(id) + "\nevent: " + type + "\ndata: " + Dump(data) + "\n\n");
  }
  bool SendResync(httplib::DataSink& sink) {
    service::FeatureQuery query;
    query.max_wait_s = 0;  // the changes after this snapshot follow in the queue
    std::vector<service::PlaneView> planes;
    const std::vector<service::FusedView> lines = core->QueryFeatures(query, &version, &planes);
    return Event(sink, "resync", version, MapJson(version, lines, planes));
  }
  bool SendChange(httplib::DataSink& sink, const service::MapChange& c) {
    if (c.to_version <= version) return true;  // in what the client holds already
    version = c.to_version;
    if (c.empty()) return true;
    return Event(sink, "change", c.to_version, ChangeJson(c));
  }
  // The next event, a ping, or nothing within kPoll; false ends the stream.
  bool Next(httplib::DataSink& sink, const std::atomic<bool>& stopping) {
    if (stopping.load()) return false;
    if (resync) {
      resync = false;
      return SendResync(sink);
    }
    if (!replay.empty()) {
      for (const service::ChangePtr& c : replay) {
        if (!SendChange(sink, *c)) return false;
      }
      replay.clear();
      return true;
    }
    service::ChangePtr change;
    switch (watcher->Take(kPoll, &change)) {
      case service::Watcher::Next::kClosed:
        return false;
      case service::Watcher::Next::kBehind:
        service::Log(service::LogLevel::kInfo, "web_events_behind",
                     {{"action", "the queue (limits.watch_queue) overflowed; resync"}});
        return SendResync(sink);
      case service::Watcher::Next::kChange:
        return SendChange(sink, *change);
      case service::Watcher::Next::kTimeout:
        break;
    }
    if (std::chrono::steady_clock::now() - last_write < kPing) return true;
    last_write = std::chrono::steady_clock::now();
    return Write(sink, ": ping\n\n");
  }
};

}  // namespace

void ServeEvents(std::shared_ptr<service::Core> core, const httplib::Request& req,
                 httplib::Response& res, const std::atomic<bool>* stopping,
                 std::atomic<int>* streams) {
  constexpr int kMaxStreams = 16;
  std::string since_text = req.get_header_value("Last-Event-ID");
  if (since_text.empty()) since_text = req.get_param_value("since");
  uint64_t since = 0;
  if (!since_text.empty() && since_text != "0") {
    StatusOr<uint64_t> v = ParseId(since_text, "Last-Event-ID (a map_version)");
    if (!v.ok()) return SendError(res, v.status());
    since = *v;
  }
  if (since > core->watch_hub().version()) since = 0;  // another map: start over
  auto stream = std::make_shared<EventStream>();
  stream->core = std::move(core);
  if (streams->fetch_add(1) >= kMaxStreams) {
    streams->fetch_sub(1);
    return SendError(
        res, Status::ResourceExhausted("too many event streams open (" +
                                       std::to_string(kMaxStreams) + "); close a page and reload"));
  }
  // The hub cancels a blocked write at shutdown; here the write timeout
  // bounds it and the stream sees `stopping` within kPoll.
  StatusOr<service::WatchHub::Subscription> sub = stream->core->watch_hub().Subscribe(since, [] {});
  if (!sub.ok()) {
    streams->fetch_sub(1);
    return SendError(res, sub.status());
  }
  stream->watcher = sub->watcher;
  stream->replay = std::move(sub->replay);
  stream->resync = sub->resync;
  stream->version = since;
  res.set_header("Cache-Control", "no-store");
  res.set_chunked_content_provider(
      "text/event-stream",
      [stream, stopping](size_t /*offset*/, httplib::DataSink& sink) {
        // httplib calls this outside its handlers' try/catch: an exception
        // (bad_alloc on a huge map) must end this stream, not mapd.
        try {
          return stream->Next(sink, *stopping);
        } catch (const std::exception& e) {
          service::Log(service::LogLevel::kError, "web_events_failed", {{"error", e.what()}});
          return false;
        }
      },
      [streams](bool /*success*/) { streams->fetch_sub(1); });
}

}  // namespace mapd::web
