#include "storage/map_copy.h"

#include <algorithm>
#include <limits>
#include <memory>
#include <set>
#include <utility>
#include <vector>

namespace mapd::storage {
namespace {

std::string Id(int64_t id) { return std::to_string(id); }

// The target's side: write transactions, each followed by after_commit.
class Target {
 public:
  Target(Store& to, const MapCopyOptions& options, MapCopyReport* report)
      : to_(to), options_(options), report_(report) {}

  template <typename Fn>
  Status Write(Fn fn) {
    StatusOr<std::unique_ptr<WriteTransaction>> txn = to_.BeginWrite();
    if (!txn.ok()) return txn.status();
    MAPD_RETURN_IF_ERROR(fn(txn->get()));
    MAPD_RETURN_IF_ERROR((*txn)->Commit());
    return options_.after_commit ? options_.after_commit(*report_) : Status::Ok();
  }

  Store& store() { return to_; }

 private:
  Store& to_;
  const MapCopyOptions& options_;
  MapCopyReport* report_;
};

Status CheckEmpty(Store& to) {
  StatusOr<int64_t> newest = to.NewestObservationId();
  if (!newest.ok()) return newest.status();
  StatusOr<std::vector<SubmapMeta>> submaps = to.ListSubmaps("");
  if (!submaps.ok()) return submaps.status();
  StatusOr<std::vector<MergeRecord>> merges = to.ListMerges();
  if (!merges.ok()) return merges.status();
  StatusOr<std::vector<FusedRow>> fused = to.LoadFused();
  if (!fused.ok()) return fused.status();
  if (*newest != 0 || !submaps->empty() || !merges->empty() || !fused->empty()) {
    return Status::FailedPrecondition(
        "the target map holds data already (" + Id(*newest) + " observations, " +
        Id(static_cast<int64_t>(submaps->size())) + " submaps); a map is copied into a new one");
  }
  return Status::Ok();
}

// A tying transaction of the source: the sessions it tied, and where.
struct Tie {
  int64_t through_observation = 0;
  std::vector<const SessionFrame*> sessions;
};

// Observations in id order, in groups, with every tie replayed between the
// same two observations as in the source: the target then gives the same ids,
// tie points and tie sequence numbers.
class ObservationCopy {
 public:
  ObservationCopy(Store& from, Target& target, const MapCopyOptions& options, MapCopyReport* report)
      : from_(from), target_(target), options_(options), report_(report) {}

  Status Run() {
    StatusOr<std::vector<SessionFrame>> sessions = from_.ListSessions();
    if (!sessions.ok()) return sessions.status();
    sessions_ = std::move(sessions).value();
    for (const SessionFrame& f : sessions_) {
      by_id_[f.session_id] = &f;
      if (f.tie_seq > 0) {
        Tie& tie = ties_[f.tie_seq];
        tie.through_observation = f.tied_through_observation;
        tie.sessions.push_back(&f);
      }
    }
    next_tie_ = ties_.begin();
    const auto copy = [&](const StoredObservation& obs) -> Status {
      if (obs.id != next_id_) {
        return Status::FailedPrecondition(
            "observation " + Id(obs.id) + " follows " + Id(next_id_ - 1) +
            ": raw retention dropped observations that the map's fused state (kept in its "
            "snapshot) still depends on, and a snapshot cannot move between stores; copy a "
            "map before raw retention thins it");
      }
      ++next_id_;
      MAPD_RETURN_IF_ERROR(TiesBefore(obs.id));
      pending_.push_back(obs);
      if (static_cast<int>(pending_.size()) >= std::max(1, options_.observations_per_commit))
        return Flush();
      return Status::Ok();
    };
    MAPD_RETURN_IF_ERROR(from_.ForEachObservation(copy));
    MAPD_RETURN_IF_ERROR(Flush());
    return TiesBefore(std::numeric_limits<int64_t>::max());
  }

  // The source's session by id (nullptr if unknown).
  const SessionFrame* Session(int64_t id) const {
    auto it = by_id_.find(id);
    return it == by_id_.end() ? nullptr : it->second;
  }

 private:
  Status Flush() {
    if (pending_.empty()) return Status::Ok();
    std::vector<NewObservation> batches;
    batches.reserve(pending_.size());
    for (const StoredObservation& obs : pending_) {
      const SessionFrame* session = Session(obs.session_id);
      if (session == nullptr)
        return Status::Internal("observation " + Id(obs.id) + " names no known session");
      NewObservation o;
      o.robot = from_.RobotName(obs.robot_id);
      o.session = session->name;
      o.seq = obs.seq;
      o.stamp_ns = obs.stamp_ns;
      o.received_ns = obs.received_ns;
      o.frame_kind = session->kind;
      o.features = &obs.features;
      batches.push_back(o);
    }
    const auto write = [&](WriteTransaction* txn) -> Status {
      StatusOr<std::vector<StatusOr<InsertResult>>> results = txn->InsertObservations(batches);
      if (!results.ok()) return results.status();
      for (size_t i = 0; i < results->size(); ++i) {
        const StatusOr<InsertResult>& r = (*results)[i];
        if (!r.ok()) return r.status();
        if (!r->stored || r->observation_id != pending_[i].id) {
          return Status::Internal("observation " + Id(pending_[i].id) + " was stored as " +
                                  Id(r->observation_id) + " in the target");
        }
      }
      report_->observations += pending_.size();
      return Status::Ok();
    };
    MAPD_RETURN_IF_ERROR(target_.Write(write));
    pending_.clear();
    return Status::Ok();
  }

  // Replays, each in a transaction of its own, the ties made before
  // observation `id` was committed.
  Status TiesBefore(int64_t id) {
    for (; next_tie_ != ties_.end() && next_tie_->second.through_observation < id; ++next_tie_) {
      MAPD_RETURN_IF_ERROR(Flush());
      const Tie& tie = next_tie_->second;
      const auto write = [&](WriteTransaction* txn) -> Status {
        txn->set_tie_point(tie.through_observation);
        for (const SessionFrame* f : tie.sessions) {
          const std::string robot = from_.RobotName(f->robot_id);
          StatusOr<SessionFrame> there = target_.store().FindSession(robot, f->name);
          if (!there.ok()) {
            return Status::Internal("session '" + f->name + "' of robot '" + robot +
                                    "' is tied before its first observation");
          }
          MAPD_RETURN_IF_ERROR(txn->TieSession(there->session_id, f->T_map_frame));
        }
        if (txn->tie_seq() != next_tie_->first) {
          return Status::FailedPrecondition(
              "the target numbers tie " + Id(next_tie_->first) + " as " + Id(txn->tie_seq()) +
              "; the source's ties are not numbered 1, 2, ... (a damaged database?)");
        }
        ++report_->ties;
        return Status::Ok();
      };
      MAPD_RETURN_IF_ERROR(target_.Write(write));
    }
    return Status::Ok();
  }

  Store& from_;
  Target& target_;
  const MapCopyOptions& options_;
  MapCopyReport* report_;
  std::vector<SessionFrame> sessions_;
  std::map<int64_t, const SessionFrame*> by_id_;
  std::map<int64_t, Tie> ties_;  // by tie_seq
  std::map<int64_t, Tie>::const_iterator next_tie_;
  std::vector<StoredObservation> pending_;
  int64_t next_id_ = 1;  // ids are 1, 2, ... in a complete log
};

Status CopyFused(Store& from, Target& target, MapCopyReport* report) {
  StatusOr<std::vector<FusedRow>> lines = from.LoadFused();
  if (!lines.ok()) return lines.status();
  StatusOr<std::vector<FusedPlaneRow>> planes = from.LoadFusedPlanes();
  if (!planes.ok()) return planes.status();
  report->fused_lines = lines->size();
  report->fused_planes = planes->size();
  return target.Write([&](WriteTransaction* txn) -> Status {
    MAPD_RETURN_IF_ERROR(txn->WriteFused(*lines, {}));
    return txn->WriteFusedPlanes(*planes, {});
  });
}

// Uploaded submaps first, then merges in id order, each with the map it
// produced (so a merge of merged maps finds its inputs), then placements
// and the global map.
Status CopySubmaps(Store& from, Target& target, const ObservationCopy& observations,
                   MapCopyReport* report) {
  StatusOr<std::vector<SubmapMeta>> submaps = from.ListSubmaps("");
  if (!submaps.ok()) return submaps.status();
  std::map<int64_t, const SubmapMeta*> meta;
  for (const SubmapMeta& m : *submaps) meta[m.id] = &m;
  for (const SubmapMeta& m : *submaps) {
    if (m.robot == kMergedRobot) continue;
    StatusOr<std::string> data = from.GetSubmapData(m.id);
    if (!data.ok()) return data.status();
    NewSubmap n;
    n.meta = m;
    if (const SessionFrame* s = observations.Session(m.session_id); s != nullptr)
      n.session = s->name;
    n.data = *data;
    const auto write = [&](WriteTransaction* txn) -> Status {
      StatusOr<int64_t> id = txn->InsertSubmap(n);
      if (!id.ok()) return id.status();
      report->submap_ids[m.id] = *id;
      ++report->submaps;
      return Status::Ok();
    };
    MAPD_RETURN_IF_ERROR(target.Write(write));
  }

  StatusOr<std::vector<MergeRecord>> merges = from.ListMerges();
  if (!merges.ok()) return merges.status();
  for (const MergeRecord& rec : *merges) {
    NewMerge m;
    m.record = rec;
    for (MergeInputRecord& in : m.record.inputs) {
      auto it = report->submap_ids.find(in.submap_id);
      if (it != report->submap_ids.end()) {
        in.submap_id = it->second;
      } else if (rec.state == MergeState::kRefused) {
        in.submap_id = 0;  // deleted since: a refused merge does not pin its inputs
        ++report->unknown_merge_inputs;
      } else {
        return Status::Internal("merge " + Id(rec.id) + " names submap " + Id(in.submap_id) +
                                ", which is not stored");
      }
    }
    std::string data;
    auto merged = meta.find(rec.merged_submap_id);
    const bool has_merged = rec.merged_submap_id != 0 && merged != meta.end();
    if (has_merged) {
      StatusOr<std::string> bytes = from.GetSubmapData(rec.merged_submap_id);
      if (!bytes.ok()) return bytes.status();
      data = std::move(bytes).value();
      m.merged.meta = *merged->second;
      m.merged.data = data;
    } else if (rec.state == MergeState::kAccepted || rec.state == MergeState::kProposed) {
      return Status::Internal("merge " + Id(rec.id) + " is " + MergeStateName(rec.state) +
                              " but its merged map is not stored");
    }
    // A rejected merge keeps the map it proposed: recorded as proposed, then rejected.
    const bool reject_after = rec.state == MergeState::kRejected && has_merged;
    if (reject_after) {
      m.record.state = MergeState::kProposed;
      m.record.decided_by.clear();
      m.record.decided_ns = 0;
      m.record.reason.clear();
    }
    const auto write = [&](WriteTransaction* txn) -> Status {
      StatusOr<MergeIds> ids = txn->RecordMerge(m);
      if (!ids.ok()) return ids.status();
      if (reject_after) {
        MAPD_RETURN_IF_ERROR(txn->DecideMerge(ids->merge_id, MergeState::kRejected, rec.decided_by,
                                              rec.decided_ns, rec.reason));
      }
      report->merge_ids[rec.id] = ids->merge_id;
      ++report->merges;
      if (has_merged) {
        report->submap_ids[rec.merged_submap_id] = ids->merged_submap_id;
        ++report->submaps;
      }
      return Status::Ok();
    };
    MAPD_RETURN_IF_ERROR(target.Write(write));
  }

  StatusOr<std::vector<SubmapPlacement>> placements = from.ListPlacements();
  if (!placements.ok()) return placements.status();
  StatusOr<GlobalMapRecord> global = from.GetGlobalMap(/*with_data=*/true);
  if (!global.ok() && global.status().code() != StatusCode::kNotFound) return global.status();
  const auto submap_id = [&](int64_t id) -> StatusOr<int64_t> {
    auto it = report->submap_ids.find(id);
    if (it == report->submap_ids.end())
      return Status::Internal("submap " + Id(id) + " is placed but not stored");
    return it->second;
  };
  return target.Write([&](WriteTransaction* txn) -> Status {
    for (const SubmapPlacement& p : *placements) {
      StatusOr<int64_t> id = submap_id(p.submap_id);
      if (!id.ok()) return id.status();
      auto merge = report->merge_ids.find(p.merge_id);
      if (merge == report->merge_ids.end())
        return Status::Internal("submap " + Id(p.submap_id) + " is placed by no stored merge");
      MAPD_RETURN_IF_ERROR(txn->PlaceSubmap(*id, merge->second, p.T_map_submap));
      ++report->placements;
    }
    if (!global.ok()) return Status::Ok();
    GlobalMapRecord g = *global;
    for (GlobalMapMember& member : g.members) {
      StatusOr<int64_t> id = submap_id(member.submap_id);
      if (!id.ok()) return id.status();
      member.submap_id = *id;
    }
    report->global_map = true;
    return txn->PutGlobalMap(g);
  });
}

Status CopyAudit(Store& from, Target& target, MapCopyReport* report) {
  StatusOr<std::vector<AuditEntry>> audit = from.ListAudit(std::numeric_limits<int>::max());
  if (!audit.ok()) return audit.status();
  std::reverse(audit->begin(), audit->end());  // oldest first, as they were written
  constexpr size_t kPerCommit = 4096;
  for (size_t begin = 0; begin < audit->size(); begin += kPerCommit) {
    const size_t end = std::min(audit->size(), begin + kPerCommit);
    const auto write = [&](WriteTransaction* txn) -> Status {
      for (size_t i = begin; i < end; ++i) MAPD_RETURN_IF_ERROR(txn->AppendAudit((*audit)[i]));
      report->audit_rows += end - begin;
      return Status::Ok();
    };
    MAPD_RETURN_IF_ERROR(target.Write(write));
  }
  return Status::Ok();
}

// Before anything is written: a name taken in the target fails the copy.
StatusOr<std::vector<TokenRecord>> TokensToCopy(Store& from, Store& to,
                                                const MapCopyOptions& options) {
  if (!options.copy_tokens) return std::vector<TokenRecord>{};
  StatusOr<std::vector<TokenRecord>> tokens = from.ListTokens();
  if (!tokens.ok()) return tokens.status();
  StatusOr<std::vector<TokenRecord>> there = to.ListTokens();
  if (!there.ok()) return there.status();
  std::set<std::string> taken;
  for (const TokenRecord& t : *there) taken.insert(t.name);
  for (TokenRecord& t : *tokens) {
    if (taken.count(t.name) != 0) {
      return Status::AlreadyExists("the target has a token named '" + t.name +
                                   "' already (token names are never reused); copy without "
                                   "tokens, or revoke and rename one of them first");
    }
    if (t.maps.empty()) t.maps = options.scope_tokens_to;
  }
  return tokens;
}

Status CopyTokens(const std::vector<TokenRecord>& tokens, Target& target, MapCopyReport* report) {
  if (tokens.empty()) return Status::Ok();
  return target.Write([&](WriteTransaction* txn) -> Status {
    for (const TokenRecord& t : tokens) {
      StatusOr<int64_t> id = txn->InsertToken(t);
      if (!id.ok()) return id.status();
      if (t.revoked_ns != 0) MAPD_RETURN_IF_ERROR(txn->RevokeToken(*id, t.revoked_ns));
      ++report->tokens;
    }
    return Status::Ok();
  });
}

// The copy answers as the source does: same counts, same ties.
Status Verify(Store& from, Store& to, MapCopyReport* report) {
  StatusOr<StoreCounts> a = from.Counts();
  if (!a.ok()) return a.status();
  StatusOr<StoreCounts> b = to.Counts();
  if (!b.ok()) return b.status();
  const auto differ = [](const char* what, uint64_t x, uint64_t y) {
    return Status::Internal(std::string("the copy has ") + std::to_string(y) + " " + what +
                            ", the source " + std::to_string(x));
  };
  if (a->robots != b->robots) return differ("robots", a->robots, b->robots);
  if (a->sessions != b->sessions) return differ("sessions", a->sessions, b->sessions);
  if (a->observations != b->observations)
    return differ("observations", a->observations, b->observations);
  if (a->raw_features != b->raw_features)
    return differ("raw features", a->raw_features, b->raw_features);
  if (a->fused != b->fused) return differ("fused rows", a->fused, b->fused);
  if (a->submaps != b->submaps) return differ("submaps", a->submaps, b->submaps);
  report->robots = b->robots;
  report->sessions = b->sessions;
  StatusOr<std::vector<SessionFrame>> sessions = from.ListSessions();
  if (!sessions.ok()) return sessions.status();
  for (const SessionFrame& f : *sessions) {
    const std::string robot = from.RobotName(f.robot_id);
    StatusOr<SessionFrame> g = to.FindSession(robot, f.name);
    if (!g.ok()) return g.status();
    if (g->kind != f.kind || g->tied != f.tied ||
        g->tied_through_observation != f.tied_through_observation || g->tie_seq != f.tie_seq) {
      return Status::Internal("session '" + f.name + "' of robot '" + robot +
                              "' is tied differently in the copy");
    }
  }
  return Status::Ok();
}

}  // namespace

StatusOr<MapCopyReport> CopyMap(Store& from, Store& to, const MapCopyOptions& options) {
  MAPD_RETURN_IF_ERROR(CheckEmpty(to));
  StatusOr<std::vector<TokenRecord>> tokens = TokensToCopy(from, to, options);
  if (!tokens.ok()) return tokens.status();
  MapCopyReport report;
  Target target(to, options, &report);
  ObservationCopy observations(from, target, options, &report);
  MAPD_RETURN_IF_ERROR(observations.Run());
  MAPD_RETURN_IF_ERROR(CopyFused(from, target, &report));
  MAPD_RETURN_IF_ERROR(CopySubmaps(from, target, observations, &report));
  MAPD_RETURN_IF_ERROR(CopyAudit(from, target, &report));
  MAPD_RETURN_IF_ERROR(CopyTokens(*tokens, target, &report));
  MAPD_RETURN_IF_ERROR(Verify(from, to, &report));
  return report;
}

}  // namespace mapd::storage
