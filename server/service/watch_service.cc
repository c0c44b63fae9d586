#include "service/watch_service.h"

#include <cmath>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "service/ingest_batch.h"
#include "service/log.h"
#include "service/proto_convert.h"
#include "service/status_mapping.h"
#include "service/watch_hub.h"

namespace mapd::service {
namespace {

namespace pb = mapserver::v1;

// Entries (features, planes, ids) per message at most, as GetFeatureMap's pages.
constexpr int kEntriesPerMessage = 4096;
// How often a watch with nothing to send looks whether its client went away.
constexpr std::chrono::milliseconds kPoll{250};

int Entries(const pb::FeatureMapDelta& m) {
  return m.added_size() + m.updated_size() + m.removed_size() + m.added_planes_size() +
         m.updated_planes_size() + m.removed_planes_size();
}

// One client's view of the map: the ids it holds (so that a feature leaving
// the filter is reported removed and one entering it added) and its version.
class WatchStream {
 public:
  WatchStream(Core* core, const FeatureFilter& filter, Watcher* watcher,
              grpc::ServerWriter<pb::FeatureMapDelta>* writer)
      : core_(core), filter_(filter), watcher_(watcher), writer_(writer) {}

  uint64_t version() const { return version_; }

  // The full filtered map (resync = true on its first message).
  bool SendResync() {
    std::vector<FusedView> lines;
    std::vector<PlaneView> planes;
    const uint64_t at = Snapshot(&lines, &planes);
    lines_.clear();
    planes_.clear();
    loose_before_ = 0;  // the ids held are exactly the ones sent now
    version_ = at;
    pb::FeatureMapDelta msg;
    msg.set_map_version(at);
    msg.set_resync(true);
    for (const FusedView& v : lines) {
      lines_.insert(v.feature.id);
      ToProto(v, msg.add_added());
      if (!MaybeFlush(&msg)) return false;
    }
    for (const PlaneView& v : planes) {
      planes_.insert(v.plane.id);
      ToProto(v, msg.add_added_planes());
      if (!MaybeFlush(&msg)) return false;
    }
    return Write(msg, /*more=*/false);
  }

  // A resume from `since`: the client holds the filtered map at that
  // version, which the server cannot rebuild. It takes the ids of the map as
  // it is now instead; the ids changed between `since` and now come in the
  // changes that follow, and until those are through (changes that begin
  // before now) an id that does not pass is reported removed whether or not
  // it is believed held.
  void StartFrom(uint64_t since) {
    std::vector<FusedView> lines;
    std::vector<PlaneView> planes;
    loose_before_ = Snapshot(&lines, &planes);
    for (const FusedView& v : lines) lines_.insert(v.feature.id);
    for (const PlaneView& v : planes) planes_.insert(v.plane.id);
    version_ = since;
  }

  // One change, filtered for this client; nothing is sent when nothing of it
  // concerns the client.
  bool Send(const MapChange& c) {
    if (c.to_version <= version_) return true;  // the client has it already
    const bool loose = c.from_version < loose_before_;
    version_ = c.to_version;
    pb::FeatureMapDelta msg;
    msg.set_map_version(c.to_version);
    for (const FusedView& v : c.lines) {
      if (filter_.Matches(v)) {
        ToProto(v, lines_.insert(v.feature.id).second ? msg.add_added() : msg.add_updated());
      } else if (lines_.erase(v.feature.id) > 0 || loose) {
        msg.add_removed(v.feature.id);
      }
      if (!MaybeFlush(&msg)) return false;
    }
    for (fusion::ClusterId id : c.lines_gone) {
      if (lines_.erase(id) > 0 || loose) msg.add_removed(id);
      if (!MaybeFlush(&msg)) return false;
    }
    for (const PlaneView& v : c.planes) {
      if (filter_.Matches(v)) {
        ToProto(v, planes_.insert(v.plane.id).second ? msg.add_added_planes()
                                                     : msg.add_updated_planes());
      } else if (planes_.erase(v.plane.id) > 0 || loose) {
        msg.add_removed_planes(v.plane.id);
      }
      if (!MaybeFlush(&msg)) return false;
    }
    for (fusion::ClusterId id : c.planes_gone) {
      if (planes_.erase(id) > 0 || loose) msg.add_removed_planes(id);
      if (!MaybeFlush(&msg)) return false;
    }
    if (Entries(msg) == 0 && !sent_partial_) return true;
    return Write(msg, /*more=*/false);
  }

 private:
  // The filtered published map now (the fuser is not waited for: changes
  // after it follow in the queue) and its version.
  uint64_t Snapshot(std::vector<FusedView>* lines, std::vector<PlaneView>* planes) {
    FeatureQuery query;
    query.bbox = filter_.bbox;
    query.kind = filter_.kind;
    query.max_wait_s = 0;
    uint64_t at = 0;
    std::vector<FusedView> all = core_->QueryFeatures(query, &at, planes);
    for (FusedView& v : all) {
      if (filter_.Matches(v)) lines->push_back(std::move(v));
    }
    std::vector<PlaneView> kept;
    for (PlaneView& v : *planes) {
      if (filter_.Matches(v)) kept.push_back(std::move(v));
    }
    planes->swap(kept);
    return at;
  }

  // A full message goes out with more = true; the next one of the same
  // version carries neither resync nor the entries sent.
  bool MaybeFlush(pb::FeatureMapDelta* msg) {
    if (Entries(*msg) < kEntriesPerMessage) return true;
    if (!Write(*msg, /*more=*/true)) return false;
    const uint64_t version = msg->map_version();
    msg->Clear();
    msg->set_map_version(version);
    return true;
  }

  bool Write(pb::FeatureMapDelta& msg, bool more) {
    msg.set_more(more);
    sent_partial_ = more;
    watcher_->SetWriting(true);
    const bool ok = !watcher_->closed() && writer_->Write(msg);
    watcher_->SetWriting(false);
    return ok;
  }

  Core* const core_;
  const FeatureFilter filter_;
  Watcher* const watcher_;
  grpc::ServerWriter<pb::FeatureMapDelta>* const writer_;
  std::unordered_set<fusion::ClusterId> lines_, planes_;  // what the client holds
  uint64_t version_ = 0;
  uint64_t loose_before_ = 0;  // see StartFrom
  bool sent_partial_ = false;  // the last message had more = true
};

}  // namespace

Status ParseWatchRequest(const pb::WatchFeatureMapRequest& in, uint64_t map_version,
                         FeatureFilter* out) {
  if (in.has_bbox()) {
    geometry::Box2 box;
    MAPD_RETURN_IF_ERROR(FromProto(in.bbox(), &box));
    out->bbox = box;
  }
  MAPD_RETURN_IF_ERROR(FromProto(in.kind(), &out->kind));
  if (!in.robot_id().empty() && !ValidId(in.robot_id())) {
    return Status::InvalidArgument("robot_id is not a robot id ([A-Za-z0-9_.-], 1-128 characters)");
  }
  out->robot = in.robot_id();
  if (in.since_map_version() > map_version) {
    return Status::InvalidArgument("since_map_version " + std::to_string(in.since_map_version()) +
                                   " is newer than the map (map_version " +
                                   std::to_string(map_version) +
                                   "); use 0 or a map_version this server sent");
  }
  return Status::Ok();
}

grpc::Status ServeWatch(Core* core, grpc::ServerContext* context,
                        const pb::WatchFeatureMapRequest& request, const FeatureFilter& filter,
                        grpc::ServerWriter<pb::FeatureMapDelta>* writer) {
  StatusOr<WatchHub::Subscription> sub =
      core->watch_hub().Subscribe(request.since_map_version(), [context] { context->TryCancel(); });
  if (!sub.ok()) {
    Log(LogLevel::kWarn, "watch_refused",
        {{"peer", context->peer()}, {"why", sub.status().message()}});
    return ToGrpcStatus(sub.status());
  }
  // Unsubscribed before the call's context goes away (the hub may cancel it
  // until then).
  struct Unsubscribe {
    WatchHub& hub;
    std::shared_ptr<Watcher> watcher;
    ~Unsubscribe() { hub.Unsubscribe(watcher); }
  } unsubscribe{core->watch_hub(), sub->watcher};
  Watcher& watcher = *sub->watcher;
  WatchStream stream(core, filter, &watcher, writer);
  // Why a write failed: shutdown (WatchHub::Close cancels a blocked write)
  // or the client.
  auto gone = [&] {
    if (watcher.closed()) {
      return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                          "mapd is shutting down; watch again with since_map_version=" +
                              std::to_string(stream.version()));
    }
    return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
  };
  if (sub->resync) {
    if (!stream.SendResync()) return gone();
  } else {
    stream.StartFrom(request.since_map_version());
    for (const ChangePtr& c : sub->replay) {
      if (!stream.Send(*c)) return gone();
    }
  }
  for (;;) {
    if (context->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
    ChangePtr change;
    switch (watcher.Take(kPoll, &change)) {
      case Watcher::Next::kClosed:
        return gone();
      case Watcher::Next::kBehind:
        Log(LogLevel::kInfo, "watch_behind",
            {{"peer", context->peer()},
             {"action", "the queue (limits.watch_queue) overflowed; resync"}});
        if (!stream.SendResync()) return gone();
        break;
      case Watcher::Next::kChange:
        if (!stream.Send(*change)) return gone();
        break;
      case Watcher::Next::kTimeout:
        break;
    }
  }
}

}  // namespace mapd::service
