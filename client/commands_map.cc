// mapctl status | robots | features | maps [--archived] [create ID [--set KEY=VALUE ...] |
// delete ID [--purge] | restore ID]
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/format.h"
#include "client/format_svg.h"
#include "client/text_util.h"
#include "common/clock.h"

namespace mapd::client {
namespace {

namespace pb = mapserver::v1;

struct JsonOptions {
  bool json = false;
};

struct MapsOptions {
  bool json = false;
  bool archived = false;
};

struct FeaturesOptions {
  std::string bbox;
  uint32_t min_support = 0;
  CLI::Option* min_support_flag = nullptr;
  std::string kind = "any";
  bool raw_fit = false;
  std::string format;  // empty: from the output name
  std::string output = "-";
};

int RunStatus(const Context& ctx, const JsonOptions& flags) {
  pb::Stats stats;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->GetStats(call.get(), pb::GetStatsRequest(), &stats);
  if (!status.ok()) return ReportRpcError(ctx, "status", status);
  std::fputs(flags.json ? MessageToJson(stats).c_str() : FormatStats(stats, ctx.server).c_str(),
             stdout);
  return kExitOk;
}

int RunMaps(const Context& ctx, const MapsOptions& flags) {
  pb::ListMapsResponse maps;
  pb::ListMapsRequest request;
  request.set_archived(flags.archived);
  const grpc::Status status = ctx.stub->ListMaps(ctx.NewServerCallContext().get(), request, &maps);
  if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
    // A mapd from before maps serves exactly one, the default.
    std::printf("%-20s  %s\n", "default", "(a mapd from before maps: its only map)");
    return kExitOk;
  }
  if (!status.ok()) return ReportRpcError(ctx, "maps", status);
  if (flags.json) {
    std::fputs(MessageToJson(maps).c_str(), stdout);
    return kExitOk;
  }
  if (flags.archived) {
    std::printf("%-20s  %s\n", "ARCHIVED MAP", "ARCHIVED AT");
    for (const pb::MapInfo& m : maps.maps()) {
      std::printf("%-20s  %s\n", m.map_id().c_str(), IsoTime(m.archived_ns()).c_str());
    }
    return kExitOk;
  }
  std::printf("%-20s  %-11s  %12s  %10s  %12s  %s\n", "MAP", "STATE", "MAP VERSION", "FEATURES",
              "BATCHES", "OWN SETTINGS");
  for (const pb::MapInfo& m : maps.maps()) {
    // protobuf maps iterate in no fixed order: sorted for a stable line.
    const std::map<std::string, std::string> sorted(m.settings().begin(), m.settings().end());
    std::string settings;
    for (const auto& [key, value] : sorted) {
      if (!settings.empty()) settings += ' ';
      settings.append(key).append("=").append(value);
    }
    if (!m.served_by().empty()) {  // another mapd on the same database serves it
      std::printf("%-20s  served by %s\n", m.map_id().c_str(), m.served_by().c_str());
      continue;
    }
    std::printf(
        "%-20s  %-11s  %12llu  %10llu  %12llu  %s\n", m.map_id().c_str(),
        m.serving() ? "serving" : "not serving", static_cast<unsigned long long>(m.map_version()),
        static_cast<unsigned long long>(m.fused_features()),
        static_cast<unsigned long long>(m.batches()), settings.empty() ? "-" : settings.c_str());
  }
  if (!maps.can_create()) {
    std::printf("(one database: start mapd with --data-dir DIR to serve and create more)\n");
  }
  return kExitOk;
}

struct CreateMapOptions {
  std::string id;
  std::vector<std::string> settings;  // KEY=VALUE
};

int RunCreateMap(const Context& ctx, const CreateMapOptions& flags) {
  pb::CreateMapRequest request;
  request.set_map_id(flags.id);
  for (const std::string& kv : flags.settings) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) {
      return UsageError("maps create", "--set '" + kv + "' is not KEY=VALUE");
    }
    (*request.mutable_settings())[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  pb::MapInfo info;
  const grpc::Status status = ctx.stub->CreateMap(ctx.NewServerCallContext().get(), request, &info);
  if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
    PrintError("maps create: the server at " + ctx.server +
               " serves one map (a mapd from before maps); upgrade it to serve several");
    return kExitFailed;
  }
  if (!status.ok()) return ReportRpcError(ctx, "maps create", status);
  std::printf("created map %s\n", info.map_id().c_str());
  return kExitOk;
}

// A map-management call on the server given, or on the map's owner when
// that server names another (several mapd on one database).
template <typename Call>
grpc::Status CallMapOwner(const Context& ctx, Call call) {
  auto context = ctx.NewServerCallContext();
  grpc::Status status = call(context.get());
  if (status.error_code() != grpc::StatusCode::UNAVAILABLE) return status;
  const auto& trailers = context->GetServerTrailingMetadata();
  auto owner = trailers.find("mapd-map-owner");
  if (owner == trailers.end()) return status;
  ctx.Use(std::string(owner->second.data(), owner->second.size()));
  return call(ctx.NewServerCallContext().get());
}

struct DeleteMapOptions {
  std::string id;
  bool purge = false;
};

int RunDeleteMap(const Context& ctx, const DeleteMapOptions& flags) {
  pb::DeleteMapRequest request;
  request.set_map_id(flags.id);
  request.set_purge(flags.purge);
  pb::DeleteMapResponse response;
  const grpc::Status status = CallMapOwner(ctx, [&](grpc::ClientContext* call) {
    return ctx.stub->DeleteMap(call, request, &response);
  });
  if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
    PrintError("maps delete: the server at " + ctx.server +
               " cannot delete maps (a mapd from before DeleteMap); upgrade it");
    return kExitFailed;
  }
  if (!status.ok()) return ReportRpcError(ctx, "maps delete", status);
  if (response.purged()) {
    std::printf("deleted map %s for good\n", response.map_id().c_str());
  } else {
    std::printf("archived map %s (%s); 'mapctl maps restore %s' serves it again\n",
                response.map_id().c_str(), response.where().c_str(), response.map_id().c_str());
  }
  return kExitOk;
}

int RunRestoreMap(const Context& ctx, const CreateMapOptions& flags) {
  pb::RestoreMapRequest request;
  request.set_map_id(flags.id);
  pb::MapInfo info;
  const grpc::Status status =
      ctx.stub->RestoreMap(ctx.NewServerCallContext().get(), request, &info);
  if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
    PrintError("maps restore: the server at " + ctx.server +
               " cannot restore maps (a mapd from before RestoreMap); upgrade it");
    return kExitFailed;
  }
  if (!status.ok()) return ReportRpcError(ctx, "maps restore", status);
  std::printf("restored map %s", info.map_id().c_str());
  if (!info.served_by().empty()) std::printf(" (served by %s)", info.served_by().c_str());
  std::printf(": %llu fused features at map version %llu\n",
              static_cast<unsigned long long>(info.fused_features()),
              static_cast<unsigned long long>(info.map_version()));
  return kExitOk;
}

int RunRobots(const Context& ctx, const JsonOptions& flags) {
  pb::ListRobotsResponse robots;
  auto call = ctx.NewCallContext();
  const grpc::Status status = ctx.stub->ListRobots(call.get(), pb::ListRobotsRequest(), &robots);
  if (!status.ok()) return ReportRpcError(ctx, "robots", status);
  if (flags.json) {
    std::fputs(MessageToJson(robots).c_str(), stdout);
  } else {
    std::fputs(FormatRobots(robots, UnixNowNs()).c_str(), stdout);
  }
  return kExitOk;
}

int RunFeatures(const Context& ctx, const FeaturesOptions& flags) {
  pb::FeatureMapRequest request;
  std::string error;
  if (!flags.bbox.empty() && !ParseBbox(flags.bbox, request.mutable_bbox(), &error)) {
    return UsageError("features", error);
  }
  if (flags.min_support_flag->count() > 0) request.set_min_support(flags.min_support);
  if (flags.kind == "line") request.set_kind(pb::FEATURE_KIND_LINE);
  if (flags.kind == "plane") request.set_kind(pb::FEATURE_KIND_PLANE);
  request.set_without_corner_optimisation(flags.raw_fit);

  OutputFormat format = GuessOutputFormat(flags.output, OutputFormat::kTable);
  if (!flags.format.empty()) {
    ParseOutputFormat(flags.format, &format);  // checked by the parser
  } else if (flags.output != "-" && !HasOutputExtension(flags.output)) {
    // `features -o out.xyz` wrote a table into out.xyz.
    return UsageError("features", "cannot tell the format of '" + flags.output +
                                      "' from its name (.geojson, .json, .svg, or .txt for the "
                                      "table); give --format");
  }

  FeatureList features;
  PlaneList planes;
  uint64_t map_version = 0, fusion_pending = 0;
  auto call = ctx.NewCallContext();
  std::unique_ptr<grpc::ClientReader<pb::FeatureMapPage>> reader =
      ctx.stub->GetFeatureMap(call.get(), request);
  pb::FeatureMapPage page;
  while (reader->Read(&page)) {
    map_version = page.map_version();
    fusion_pending = page.fusion_pending();
    for (pb::FusedFeature& f : *page.mutable_features()) features.push_back(std::move(f));
    for (pb::FusedPlane& p : *page.mutable_planes()) planes.push_back(std::move(p));
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return ReportRpcError(ctx, "features", status);

  std::string text;
  switch (format) {
    case OutputFormat::kTable:
      text = FormatFeatureTable(features, planes);
      break;
    case OutputFormat::kJson:
      text = FormatFeatureJson(features, map_version, planes, fusion_pending);
      break;
    case OutputFormat::kGeoJson:
      text = FormatGeoJson(features, planes);
      break;
    case OutputFormat::kSvg:
      text = FormatSvg(features, planes);
      break;
  }
  if (!WriteOutput(flags.output, text, &error)) {
    PrintError("features: " + error);
    return kExitFailed;
  }
  if (flags.output != "-") {
    std::printf("wrote %zu features and %zu planes (map version %llu) to %s\n", features.size(),
                planes.size(), static_cast<unsigned long long>(map_version), flags.output.c_str());
  }
  return kExitOk;
}

}  // namespace

bool ParseBbox(const std::string& text, mapserver::v1::BoundingBox2* out, std::string* error) {
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

void AddMapCommands(CLI::App* app, Action* action) {
  CLI::App* status = app->add_subcommand("status", "server statistics");
  status->footer(
      "Robots, sessions, batches, raw and fused features, clusters, ingest rate, uptime,\n"
      "database size and path, version.");
  status->add_flag(
      "--json", BindCommand(status, action, RunStatus)->json,
      "the Stats message in protobuf JSON (.proto field names; 64-bit counts are strings)");

  CLI::App* maps =
      app->add_subcommand("maps", "the maps the server serves; maps create | delete | restore ID");
  maps->footer(
      "Each map is its own map frame, fused map, submaps and merges; name one with\n"
      "'mapctl --map ID <command>' or $MAPD_MAP. mapd --data-dir serves several.\n"
      "A deleted map is archived (kept, unserved) until restored or deleted --purge.");
  // Not BindCommand: CLI11 runs this callback after `create`'s, whose action stays.
  auto list = std::make_shared<MapsOptions>();
  maps->callback([maps, list, action] {
    if (!maps->get_subcommands().empty()) return;
    *action = [list](const Context& ctx) { return RunMaps(ctx, *list); };
  });
  maps->add_flag("--json", list->json, "the ListMapsResponse in protobuf JSON");
  maps->add_flag("--archived", list->archived, "the archived maps instead (maps delete ID)");
  CLI::App* create = maps->add_subcommand("create", "make a new, empty map (role admin)");
  auto created = BindCommand(create, action, RunCreateMap);
  create
      ->add_option("id", created->id,
                   "the map id: 1-128 characters of [A-Za-z0-9_.-], not starting with '.'")
      ->required();
  create
      ->add_option("--set", created->settings,
                   "KEY=VALUE: the map's own setting over mapd's, for fusion.*, planes.* and "
                   "merge.* keys (mapd --help); repeat for more")
      ->take_all();
  CLI::App* remove = maps->add_subcommand(
      "delete", "stop serving a map and archive it, or delete it for good (role admin)");
  remove->footer(
      "Its robots' streams end (they resend to nobody until it is restored), calls for it\n"
      "are NOT_FOUND. Archived: mapd --data-dir moves its files to DIR/archive/, a\n"
      "PostgreSQL map keeps its rows; 'maps restore ID' serves it again as it was.\n"
      "--purge deletes its data for good (an archived map's too). Not the default map.");
  auto removed = BindCommand(remove, action, RunDeleteMap);
  remove->add_option("id", removed->id, "the map id")->required();
  remove->add_flag("--purge", removed->purge, "delete its data for good instead of archiving it");
  CLI::App* restore =
      maps->add_subcommand("restore", "serve an archived map again, as it was (role admin)");
  restore->add_option("id", BindCommand(restore, action, RunRestoreMap)->id, "the map id")
      ->required();

  CLI::App* robots =
      app->add_subcommand("robots", "the robots seen, with their sessions and counts");
  robots->footer(
      "Sessions, stored batches and features, whether their frames are tied to the map\n"
      "frame, first and last seen (UTC).");
  robots->add_flag("--json", BindCommand(robots, action, RunRobots)->json,
                   "the ListRobotsResponse in protobuf JSON");

  CLI::App* features =
      app->add_subcommand("features", "query / export the fused map (table, json, geojson, svg)");
  features->footer(
      "The fused feature map (map frame, metres): walls as segments, then floors, ceilings\n"
      "and ramps as planes (id, normal, offset, area, support, robots).");
  auto f = BindCommand(features, action, RunFeatures);
  features->add_option(
      "--bbox", f->bbox,
      "XMIN,YMIN,XMAX,YMAX: only features whose segment meets this box, and planes whose "
      "boundary's ground projection meets it");
  f->min_support_flag =
      features->add_option("--min-support", f->min_support,
                           "only features seen in at least N observations (values below "
                           "the server's threshold are raised to it)");
  features->add_option("--kind", f->kind, "only this kind (line leaves out the planes)")
      ->capture_default_str()
      ->check(CLI::IsMember({"line", "plane", "any"}));
  features->add_flag("--raw-fit", f->raw_fit,
                     "the raw least-squares fit, not the corner-optimised segment");
  features
      ->add_option("--format", f->format,
                   "default: from the -o extension (.json, .geojson, .svg), else table")
      ->check(CLI::IsMember({"table", "json", "geojson", "svg"}));
  features->add_option("-o,--output", f->output, "write to FILE (- for stdout)")
      ->capture_default_str();
}

}  // namespace mapd::client
