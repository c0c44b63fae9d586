// mapctl status | robots | features
#include <cstdio>

#include "client/commands.h"
#include "client/format.h"
#include "common/clock.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

const char kStatusHelp[] =
    "Usage: mapctl status [--json]\n"
    "Server statistics: robots, sessions, batches, raw and fused features, clusters,\n"
    "ingest rate, uptime, database size and path, version.\n"
    "  --json   the Stats message in protobuf JSON (64-bit counts are strings)\n";

const char kRobotsHelp[] =
    "Usage: mapctl robots [--json]\n"
    "The robots the server has seen: sessions, stored batches and features, whether\n"
    "their frames are tied to the map frame, first and last seen (UTC).\n"
    "  --json   the ListRobotsResponse in protobuf JSON\n";

const char kFeaturesHelp[] =
    "Usage: mapctl features [options]\n"
    "The fused feature map (map frame, metres): walls as segments, then floors,\n"
    "ceilings and ramps as planes (id, normal, offset, area, support, robots).\n"
    "  --bbox XMIN,YMIN,XMAX,YMAX  only features whose segment meets this box, and planes\n"
    "                              whose boundary's ground projection meets it\n"
    "  --min-support N             only features seen in at least N observations\n"
    "                              (values below the server's threshold are raised to it)\n"
    "  --kind line|plane|any       only this kind (default any; line leaves out the planes)\n"
    "  --raw-fit                   the raw least-squares fit, not the corner-optimised segment\n"
    "  --format table|json|geojson|svg\n"
    "                              default: from the -o extension (.json, .geojson, .svg), else table\n"
    "  -o, --output FILE           write to FILE (default: stdout)\n";

// "xmin,ymin,xmax,ymax" -> bbox; false with `*error` set otherwise.
bool ParseBbox(const std::string& text, pb::BoundingBox2* out, std::string* error) {
  const std::vector<std::string> parts = Split(text, ',');
  double v[4];
  if (parts.size() != 4) {
    *error = "--bbox wants XMIN,YMIN,XMAX,YMAX (4 numbers, metres), got '" + text + "'";
    return false;
  }
  for (size_t i = 0; i < 4; ++i) {
    if (!ParseDouble(parts[i], &v[i])) {
      *error = "--bbox: '" + parts[i] + "' is not a number";
      return false;
    }
  }
  if (v[0] > v[2] || v[1] > v[3]) {
    *error = "--bbox: XMIN must not exceed XMAX, nor YMIN YMAX, got '" + text + "'";
    return false;
  }
  out->mutable_min()->set_x(v[0]);
  out->mutable_min()->set_y(v[1]);
  out->mutable_max()->set_x(v[2]);
  out->mutable_max()->set_y(v[3]);
  return true;
}

}  // namespace

int RunStatus(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("status", kStatusHelp, args, {{"--json"}}, &flags); rc != kContinue) return rc;
  if (!flags.positionals().empty()) return UsageError("status", "unexpected argument '" + flags.positionals()[0] + "'");
  pb::Stats stats;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->GetStats(call.get(), pb::GetStatsRequest(), &stats);
  if (!status.ok()) return ReportRpcError(ctx, "status", status);
  std::fputs(flags.Has("--json") ? MessageToJson(stats).c_str() : FormatStats(stats, ctx.server).c_str(), stdout);
  return kExitOk;
}

int RunRobots(const Context& ctx, const CommandArgs& args) {
  Args flags;
  if (int rc = ParseCommandArgs("robots", kRobotsHelp, args, {{"--json"}}, &flags); rc != kContinue) return rc;
  if (!flags.positionals().empty()) return UsageError("robots", "unexpected argument '" + flags.positionals()[0] + "'");
  pb::ListRobotsResponse robots;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListRobots(call.get(), pb::ListRobotsRequest(), &robots);
  if (!status.ok()) return ReportRpcError(ctx, "robots", status);
  if (flags.Has("--json")) {
    std::fputs(MessageToJson(robots).c_str(), stdout);
  } else {
    std::fputs(FormatRobots(robots, UnixNowNs()).c_str(), stdout);
  }
  return kExitOk;
}

int RunFeatures(const Context& ctx, const CommandArgs& args) {
  Args flags;
  const std::vector<FlagSpec> specs = {{"--bbox", true},   {"--min-support", true}, {"--kind", true},
                                       {"--raw-fit", false}, {"--format", true},      {"-o", true},
                                       {"--output", true}};
  if (int rc = ParseCommandArgs("features", kFeaturesHelp, args, specs, &flags); rc != kContinue) return rc;
  if (!flags.positionals().empty()) {
    return UsageError("features", "unexpected argument '" + flags.positionals()[0] + "'");
  }

  pb::FeatureMapRequest request;
  std::string error;
  if (flags.Has("--bbox") && !ParseBbox(flags.Get("--bbox"), request.mutable_bbox(), &error)) {
    return UsageError("features", error);
  }
  if (flags.Has("--min-support")) {
    uint64_t n = 0;
    if (!ParseUint(flags.Get("--min-support"), &n) || n > UINT32_MAX) {
      return UsageError("features", "--min-support wants a count, got '" + flags.Get("--min-support") + "'");
    }
    request.set_min_support(static_cast<uint32_t>(n));
  }
  const std::string kind = flags.Get("--kind", "any");
  if (kind == "line") request.set_kind(pb::FEATURE_KIND_LINE);
  else if (kind == "plane") request.set_kind(pb::FEATURE_KIND_PLANE);
  else if (kind != "any") return UsageError("features", "--kind wants line, plane or any, got '" + kind + "'");
  request.set_without_corner_optimisation(flags.Has("--raw-fit"));

  const std::string output = flags.Get("-o", flags.Get("--output", "-"));
  OutputFormat format = GuessOutputFormat(output, OutputFormat::kTable);
  if (flags.Has("--format") && !ParseOutputFormat(flags.Get("--format"), &format)) {
    return UsageError("features", "--format wants table, json, geojson or svg, got '" + flags.Get("--format") + "'");
  }

  FeatureList features;
  PlaneList planes;
  uint64_t map_version = 0;
  auto call = ctx.NewCallContext();
  std::unique_ptr<grpc::ClientReader<pb::FeatureMapPage>> reader = ctx.stub->GetFeatureMap(call.get(), request);
  pb::FeatureMapPage page;
  while (reader->Read(&page)) {
    map_version = page.map_version();
    for (pb::FusedFeature& f : *page.mutable_features()) features.push_back(std::move(f));
    for (pb::FusedPlane& p : *page.mutable_planes()) planes.push_back(std::move(p));
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return ReportRpcError(ctx, "features", status);

  std::string text;
  switch (format) {
    case OutputFormat::kTable: text = FormatFeatureTable(features, planes); break;
    case OutputFormat::kJson: text = FormatFeatureJson(features, map_version, planes); break;
    case OutputFormat::kGeoJson: text = FormatGeoJson(features, planes); break;
    case OutputFormat::kSvg: text = FormatSvg(features, planes); break;
  }
  if (!WriteOutput(output, text, &error)) {
    PrintError("features: " + error);
    return kExitFailed;
  }
  if (output != "-") {
    std::printf("wrote %zu features and %zu planes (map version %llu) to %s\n", features.size(), planes.size(),
                static_cast<unsigned long long>(map_version), output.c_str());
  }
  return kExitOk;
}

}  // namespace mapd::client
