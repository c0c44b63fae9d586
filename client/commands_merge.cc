// mapctl merge | merge show|approve|reject | merges
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "client/commands.h"
#include "client/format.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct MergeOptions {
  std::vector<uint64_t> ids;
  bool wait = false;
  bool review = false;
  std::string render;
};

struct MergesOptions {
  std::string state;  // empty: all
  bool json = false;
};

struct ShowOptions {
  uint64_t id = 0;
  std::string render;
  bool json = false;
};

struct DecideOptions {
  uint64_t id = 0;
  std::string reason;  // reject only
};

std::string FormatMergeProgress(const pb::MergeProgress& p) {
  const double percent = std::floor(100 * std::clamp(p.fraction(), 0.0, 1.0));
  return Printf("merge: %-10s %3.0f%%", p.stage().c_str(), percent);
}

// Per submap: where it sits in the reference (first) submap's frame and the evidence for it.
std::string FormatMergeResult(const pb::MergeResult& result) {
  const bool proposed = result.state() == pb::MERGE_STATE_PROPOSED;
  std::string out = Printf("merge %llu %s: merged submap %llu\n",
                           static_cast<unsigned long long>(result.merge_id()),
                           proposed ? "proposed (waits for review)" : "accepted",
                           static_cast<unsigned long long>(result.merged_submap_id()));
  for (const pb::SubmapAlignment& a : result.alignments()) out += FormatAlignment(a);
  if (proposed) {
    out += Printf(
        "nothing changes until 'mapctl merge approve %llu' ('mapctl merge reject %llu "
        "--reason ...' ends it)\n",
        static_cast<unsigned long long>(result.merge_id()),
        static_cast<unsigned long long>(result.merge_id()));
  }
  return out;
}

// Draws each input in its own colour, moved by its transform (the first input
// is the reference frame): walls that line up show the merge is right.
int RenderAlignedInputs(const Context& ctx, const std::string& command,
                        const google::protobuf::RepeatedPtrField<pb::SubmapAlignment>& alignments,
                        const std::string& path, ImageFormat format) {
  std::vector<VoxelLayer> layers;
  for (int i = 0; i < alignments.size(); ++i) {
    const pb::SubmapAlignment& a = alignments.Get(i);
    const uint64_t id = a.submap_id();
    geometry::Rigid3 T_reference_submap;
    if (a.has_t_reference_submap()) {
      T_reference_submap = ToRigid3(a.t_reference_submap());
    } else if (i > 0) {
      PrintError(Printf("%s: no transform for submap %llu; not drawn", command.c_str(),
                        static_cast<unsigned long long>(id)));
      continue;
    }
    std::string data;
    pb::SubmapInfo info;
    auto get_call = ctx.NewStreamContext();
    pb::GetSubmapRequest get_request;
    get_request.set_id(id);
    const grpc::Status get_status =
        ReadChunks(ctx.stub->GetSubmap(get_call.get(), get_request).get(), &data, &info);
    if (!get_status.ok()) {
      return ReportRpcError(
          ctx, Printf("%s: GetSubmap %llu", command.c_str(), static_cast<unsigned long long>(id)),
          get_status);
    }
    const std::string what =
        Printf("submap %llu (robot %s, %s)", static_cast<unsigned long long>(id),
               info.robot_id().c_str(), info.name().c_str());
    if (int rc = AddRenderLayer(command, what, data, T_reference_submap, &layers); rc != kContinue)
      return rc;
  }
  return WriteRendering(command, layers, path, format);
}

int RunMerge(const Context& ctx, const MergeOptions& flags) {
  pb::MergeSubmapsRequest request;
  for (uint64_t id : flags.ids) request.add_submap_ids(id);
  request.set_review(flags.review);
  if (request.submap_ids_size() < 2) return UsageError("merge", "wants two or more submap ids");
  const std::string& render_path = flags.render;
  ImageFormat render_format = ImageFormat::kPng;
  if (!render_path.empty()) {
    if (int rc = CheckRenderOutput("merge", render_path, &render_format); rc != kContinue)
      return rc;
  }

  auto call = ctx.NewStreamContext();  // no deadline: a merge takes as long as it takes
  std::unique_ptr<grpc::ClientReader<pb::MergeProgress>> reader =
      ctx.stub->MergeSubmaps(call.get(), request);
  pb::MergeProgress progress;
  bool have_result = false;
  pb::MergeResult result;
  std::string last_line;
  while (reader->Read(&progress)) {
    if (progress.has_result()) {
      result = progress.result();
      have_result = true;
    }
    if (!flags.wait) continue;
    // One line per change of stage or whole percent, flushed so that a pipe
    // shows it as it arrives.
    const std::string line = FormatMergeProgress(progress);
    if (line != last_line) {
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
      last_line = line;
    }
  }
  const grpc::Status status = reader->Finish();
  if (status.error_code() == grpc::StatusCode::FAILED_PRECONDITION) {
    // The evidence was too weak: the server says why, nothing was written.
    return ReportRpcError(ctx, "merge refused", status);
  }
  if (!status.ok()) return ReportRpcError(ctx, "merge", status);
  if (!have_result) {
    PrintError("merge: the server ended the merge without a result");
    return kExitFailed;
  }
  std::printf("%s", FormatMergeResult(result).c_str());
  std::fflush(stdout);
  if (render_path.empty()) return kExitOk;
  // In request order, the reference first, whatever order the result lists them in.
  google::protobuf::RepeatedPtrField<pb::SubmapAlignment> ordered;
  for (uint64_t id : flags.ids) {
    pb::SubmapAlignment* a = ordered.Add();
    a->set_submap_id(id);
    for (const pb::SubmapAlignment& r : result.alignments()) {
      if (r.submap_id() == id) *a = r;
    }
  }
  return RenderAlignedInputs(ctx, "merge", ordered, render_path, render_format);
}

int RunMerges(const Context& ctx, const MergesOptions& flags) {
  static const std::map<std::string, pb::MergeState> kStates = {
      {"proposed", pb::MERGE_STATE_PROPOSED},
      {"accepted", pb::MERGE_STATE_ACCEPTED},
      {"rejected", pb::MERGE_STATE_REJECTED},
      {"refused", pb::MERGE_STATE_REFUSED}};
  pb::ListMergesRequest request;
  if (!flags.state.empty()) request.set_state(kStates.at(flags.state));  // checked by CLI11
  pb::ListMergesResponse response;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListMerges(call.get(), request, &response);
  if (!status.ok()) return ReportRpcError(ctx, "merges", status);
  std::fputs(flags.json ? FormatMergesJson(response).c_str() : FormatMerges(response).c_str(),
             stdout);
  return kExitOk;
}

int RunShow(const Context& ctx, const ShowOptions& flags) {
  ImageFormat render_format = ImageFormat::kPng;
  if (!flags.render.empty()) {
    if (int rc = CheckRenderOutput("merge show", flags.render, &render_format); rc != kContinue)
      return rc;
  }
  pb::GetMergeRequest request;
  request.set_id(flags.id);
  pb::MergeRecord merge;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->GetMerge(call.get(), request, &merge);
  if (!status.ok())
    return ReportRpcError(ctx, Printf("merge show %llu", static_cast<unsigned long long>(flags.id)),
                          status);
  std::fputs(flags.json ? FormatMergeRecordJson(merge).c_str() : FormatMergeRecord(merge).c_str(),
             stdout);
  std::fflush(stdout);
  if (flags.render.empty()) return kExitOk;
  if (merge.state() == pb::MERGE_STATE_REFUSED) {
    PrintError(Printf("merge show: merge %llu was refused: it has no transforms to draw",
                      static_cast<unsigned long long>(merge.id())));
    return kExitFailed;
  }
  return RenderAlignedInputs(ctx, "merge show", merge.inputs(), flags.render, render_format);
}

int RunApprove(const Context& ctx, const DecideOptions& flags) {
  pb::ApproveMergeRequest request;
  request.set_id(flags.id);
  pb::MergeRecord merge;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ApproveMerge(call.get(), request, &merge);
  if (!status.ok()) {
    return ReportRpcError(
        ctx, Printf("merge approve %llu", static_cast<unsigned long long>(flags.id)), status);
  }
  std::fputs(FormatMergeRecord(merge).c_str(), stdout);
  return kExitOk;
}

int RunReject(const Context& ctx, const DecideOptions& flags) {
  pb::RejectMergeRequest request;
  request.set_id(flags.id);
  request.set_reason(flags.reason);
  pb::MergeRecord merge;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->RejectMerge(call.get(), request, &merge);
  if (!status.ok()) {
    return ReportRpcError(
        ctx, Printf("merge reject %llu", static_cast<unsigned long long>(flags.id)), status);
  }
  std::fputs(FormatMergeRecord(merge).c_str(), stdout);
  return kExitOk;
}

}  // namespace

void AddMergeCommands(CLI::App* app, Action* action) {
  CLI::App* merge = app->add_subcommand(
      "merge",
      "merge two or more submaps (--wait: progress, --render: picture, --review: propose only); "
      "merge show|approve|reject ID");
  merge->footer(
      "Merges two or more submaps without a prior pose and prints, per submap, where it sits\n"
      "in the first submap's frame (xyz in metres, yaw/pitch/roll in degrees, Z-Y-X), the\n"
      "matched corners, the residual and the overlap score, and the id of the merged map.\n"
      "A merge refused for weak evidence prints the server's reason and exits 1.\n"
      "With --review (or a server running with merge.review = true) an accepted merge is\n"
      "only proposed: no robot frame is tied and the global map stays until\n"
      "'mapctl merge approve ID'. 'mapctl merges' lists every merge.");
  // Not BindCommand: CLI11 runs this callback after a chosen subcommand's,
  // which must keep its action.
  auto m = std::make_shared<MergeOptions>();
  merge->callback([merge, m, action] {
    if (!merge->get_subcommands().empty()) return;
    *action = [m](const Context& ctx) { return RunMerge(ctx, *m); };
  });
  merge->add_option("ID", m->ids, "submap ids (two or more; the first is the reference frame)")
      ->expected(0, 1 << 20)
      ->check(PositiveId());
  merge->add_flag(
      "--wait", m->wait,
      "show the progress (stage and percent) while the merge runs (the call always lasts until "
      "the merge ends)");
  merge->add_flag("--review", m->review,
                  "store an accepted merge as proposed: it changes nothing until approved");
  merge->add_option(
      "--render", m->render,
      "OUT.png|OUT.svg: after an accepted merge, draw the input submaps from above, each in its "
      "own colour, moved by its transform: walls that line up show the merge is right "
      "(see 'mapctl render --help')");

  CLI::App* show = merge->add_subcommand("show", "show a stored merge (--render: picture)");
  show->footer(
      "Prints a stored merge: state, who asked and when, who decided, the reason, and per\n"
      "input submap its transform and evidence.");
  auto s = BindCommand(show, action, RunShow);
  show->add_option("ID", s->id, "the merge id (see 'mapctl merges')")
      ->required()
      ->check(PositiveId());
  show->add_option("--render", s->render,
                   "OUT.png|OUT.svg: draw the input submaps from above, each moved by its "
                   "transform (see 'mapctl merge --help')");
  show->add_flag("--json", s->json, "the merge as JSON (keys as in 'mapctl merges --json')");

  CLI::App* approve = merge->add_subcommand(
      "approve", "approve a proposed merge: ties the robots' frames, updates the global map");
  approve->footer(
      "Refused (exit 1, the server's reason) when the merge is not proposed, when one of its\n"
      "submaps was deleted, or when a merge accepted since shares a submap or robot frame.");
  auto a = BindCommand(approve, action, RunApprove);
  approve->add_option("ID", a->id, "the merge id")->required()->check(PositiveId());

  CLI::App* reject = merge->add_subcommand("reject", "reject a proposed merge (no effect)");
  auto r = BindCommand(reject, action, RunReject);
  reject->add_option("ID", r->id, "the merge id")->required()->check(PositiveId());
  reject->add_option("--reason", r->reason, "why, for the record (required)")->required();

  CLI::App* merges = app->add_subcommand("merges", "list stored merges and their state");
  merges->footer(
      "Every merge: id, state (proposed, accepted, rejected, refused), input submaps, merged\n"
      "submap, the weakest input's matched corners, residual (m) and overlap, who asked and\n"
      "when (UTC), who decided, and the reason of a refusal or rejection.");
  auto l = BindCommand(merges, action, RunMerges);
  merges->add_option("--state", l->state, "only merges in this state")
      ->check(CLI::IsMember({"proposed", "accepted", "rejected", "refused"}));
  merges->add_flag("--json", l->json, "as JSON (snake_case keys; see client/format.h)");
}

}  // namespace mapd::client
