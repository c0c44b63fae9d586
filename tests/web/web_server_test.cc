// The web view's endpoints on a real MapServer: JSON shapes, the event
// stream (resync, changes, resume), robots, metrics, merges and who may
// decide them, bad requests, and a port that is taken.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <regex>
#include <set>
#include <sstream>

#include "common/octomap_scenes.h"
#include "common/process.h"
#include "web/sse_client.h"
#include "web/web_fixture.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

TEST_F(WebFixture, FeaturesAreTheFusedMapWithTheProtosNames) {
  Start();
  Ingest(RoomBatches("r1", 8));
  const json doc = GetJson("/api/features");
  EXPECT_GT(doc["map_version"].get<uint64_t>(), 0u);
  ASSERT_EQ(doc["features"].size(), 4u) << doc.dump();  // the room's four walls
  EXPECT_TRUE(doc["planes"].is_array());
  for (const json& f : doc["features"]) {
    EXPECT_TRUE(f["id"].is_number_unsigned());
    EXPECT_EQ(f["kind"], "line");
    EXPECT_TRUE(f["a"]["x"].is_number() && f["b"]["y"].is_number()) << f.dump();
    EXPECT_TRUE(f["z_min"].is_number() && f["z_max"].is_number());
    EXPECT_GE(f["support"].get<int>(), 3);
    EXPECT_GE(f["member_count"].get<int>(), 3);
    EXPECT_EQ(f["robots"], json::array({"r1"}));
  }
}

TEST_F(WebFixture, EachMapIsShownApartAndThePickerListsThem) {
  config_.db_path.clear();
  config_.data_dir = dir_.path();
  Start();
  grpc::ClientContext create;
  pb::CreateMapRequest request;
  request.set_map_id("site-7");
  pb::MapInfo info;
  ASSERT_TRUE(stub_->CreateMap(&create, request, &info).ok());
  grpc::ClientContext ctx;
  ctx.AddMetadata("mapd-map-id", "site-7");
  auto stream = stub_->Ingest(&ctx);
  for (const auto& b : RoomBatches("r1", 8)) ASSERT_TRUE(stream->Write(b));
  stream->WritesDone();
  pb::IngestAck ack;
  while (stream->Read(&ack)) EXPECT_EQ(ack.result(), pb::IngestAck::STORED);
  ASSERT_TRUE(stream->Finish().ok());

  EXPECT_EQ(GetJson("/api/maps")["maps"], json::array({"default", "site-7"}));
  EXPECT_EQ(GetJson("/api/features?map=site-7")["features"].size(), 4u);
  EXPECT_EQ(GetJson("/api/features")["features"].size(), 0u);  // the default map
  EXPECT_EQ(GetJson("/api/robots?map=site-7")["robots"].size(), 1u);
  const json missing = GetJson("/api/features?map=site-9", 404);
  EXPECT_NE(missing["error"].get<std::string>().find("site-9"), std::string::npos);
  // A token scoped to site-7 sees that map only.
  const std::string scoped = MakeToken(service::Role::kReader, "site-7-view", {"site-7"});
  EXPECT_EQ(GetJson("/api/maps", 200, scoped)["maps"], json::array({"site-7"}));
  EXPECT_EQ(GetJson("/api/features?map=site-7", 200, scoped)["features"].size(), 4u);
  GetJson("/api/features", 403, scoped);
}

TEST_F(WebFixture, ThePageIsServedWithItsScript) {
  Start();
  httplib::Result r = Client().Get("/");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_THAT(r->get_header_value("Content-Type"), HasSubstr("text/html"));
  EXPECT_THAT(r->body, HasSubstr("/api/events"));
  EXPECT_THAT(r->body, ::testing::Not(HasSubstr("https://")));  // nothing fetched from elsewhere
  EXPECT_EQ(Client().Get("/nope")->status, 404);
}

TEST_F(WebFixture, EventsStartWithAResyncThenCarryChanges) {
  Start();
  Ingest(RoomBatches("r1", 8));
  // A resync is the map as fused so far, without waiting for the fuser; the
  // features query waits, so after it the resync holds the room.
  ASSERT_EQ(GetJson("/api/features")["features"].size(), 4u);
  SseClient events(web_->port(), {});
  std::optional<SseEvent> e = events.Next();
  ASSERT_TRUE(e);
  EXPECT_EQ(events.status(), 200);
  ASSERT_EQ(e->type, "resync");
  const json resync = json::parse(e->data);
  EXPECT_EQ(resync["features"].size(), 4u);
  EXPECT_EQ(e->id, std::to_string(resync["map_version"].get<uint64_t>()));

  // A new wall: its feature arrives in a change, once published (min_support 3).
  Ingest(FarWallBatches("r2", 4));
  std::set<uint64_t> added;
  while (added.empty()) {
    e = events.Next();
    ASSERT_TRUE(e) << "no change event with the new wall";
    ASSERT_EQ(e->type, "change");
    const json c = json::parse(e->data);
    EXPECT_EQ(e->id, std::to_string(c["map_version"].get<uint64_t>()));
    EXPECT_TRUE(c["removed"].is_array() && c["removed_planes"].is_array());
    for (const json& f : c["features"]) {
      if (f["robots"] == json::array({"r2"})) added.insert(f["id"].get<uint64_t>());
    }
  }
  const json doc = GetJson("/api/features");
  std::set<uint64_t> now;
  for (const json& f : doc["features"]) now.insert(f["id"].get<uint64_t>());
  for (uint64_t id : added) EXPECT_TRUE(now.count(id)) << id;
}

TEST_F(WebFixture, LastEventIdResumesWithChangesOrResyncs) {
  Start();
  Ingest(RoomBatches("r1", 8));
  const uint64_t v = GetJson("/api/features")["map_version"];
  Ingest(FarWallBatches("r2", 4));
  {
    SseClient events(web_->port(), {{"Last-Event-ID", std::to_string(v)}});
    std::optional<SseEvent> e = events.Next();
    ASSERT_TRUE(e);
    EXPECT_EQ(e->type, "change") << "a resume within the history gets the changes after it";
    EXPECT_GT(std::stoull(e->id), v);
  }
  {
    // Newer than the map (another database): the whole map.
    SseClient events(web_->port(), {{"Last-Event-ID", "999999999"}});
    std::optional<SseEvent> e = events.Next();
    ASSERT_TRUE(e);
    EXPECT_EQ(e->type, "resync");
  }
  const json bad = GetJson("/api/events?since=abc", 400);
  EXPECT_THAT(bad["error"].get<std::string>(),
              HasSubstr("'abc' is not a positive decimal integer"));
}

TEST_F(WebFixture, RobotsHaveTheirLastPoseAndATrail) {
  Start();
  Ingest(RoomBatches("r1", 5, 3.0, 2.0));
  const json doc = GetJson("/api/robots");
  ASSERT_EQ(doc["robots"].size(), 1u);
  const json& r = doc["robots"][0];
  EXPECT_EQ(r["robot_id"], "r1");
  EXPECT_EQ(r["batches"], 5);
  EXPECT_EQ(r["frame"], "map");
  EXPECT_NEAR(r["pose"]["x"].get<double>(), 3.4, 1e-9);  // the fifth batch's
  EXPECT_NEAR(r["pose"]["y"].get<double>(), 2.0, 1e-9);
  EXPECT_NEAR(r["pose"]["yaw"].get<double>(), 0.8, 1e-9);
  EXPECT_EQ(r["pose"]["seq"], 5);
  EXPECT_EQ(r["trail"].size(), 5u);
}

// Every sample line is `name{labels} value`, every family has HELP and TYPE.
TEST_F(WebFixture, MetricsAreValidPrometheusText) {
  Start();
  Ingest(RoomBatches("r1", 6));
  httplib::Result r = Client().Get("/metrics");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200);
  EXPECT_THAT(r->get_header_value("Content-Type"), HasSubstr("text/plain; version=0.0.4"));
  std::map<std::string, std::string> types;
  std::map<std::string, double> values;
  const std::regex sample(R"(^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[^}]*\})? (\S+)$)");
  std::istringstream in(r->body);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (line.rfind("# TYPE ", 0) == 0) {
      std::istringstream t(line.substr(7));
      std::string name, type;
      t >> name >> type;
      types[name] = type;
    } else if (line.rfind("# HELP ", 0) != 0) {
      ASSERT_TRUE(std::regex_match(line, m, sample)) << "not a sample: " << line;
      values[m[1].str() + m[2].str()] = std::stod(m[3].str());
    }
  }
  EXPECT_EQ(types["mapd_ingest_batches_total"], "counter");
  EXPECT_EQ(types["mapd_ack_latency_seconds"], "histogram");
  for (const char* g :
       {"mapd_fusion_backlog", "mapd_db_size_bytes", "mapd_merges", "mapd_watchers",
        "mapd_build_info", "process_resident_memory_bytes", "process_virtual_memory_bytes",
        "process_start_time_seconds", "process_open_fds", "process_max_fds"})
    EXPECT_EQ(types[g], "gauge") << g;
  EXPECT_EQ(types["process_cpu_seconds_total"], "counter");
  // A rate is rate()'s job, not a gauge's.
  EXPECT_EQ(types.count("mapd_ingest_batches_per_second"), 0u);
  // Bucket bounds as written, so that {le="0.005"} matches (it printed
  // 0.0050000000000000001 before).
  EXPECT_EQ(values.count("mapd_ack_latency_seconds_bucket{le=\"0.005\"}"), 1u);
  EXPECT_EQ(values.count("mapd_ack_latency_seconds_bucket{le=\"10\"}"), 1u);
  for (const auto& [name, value] : values) {
    if (name.rfind("mapd_ack_latency_seconds_bucket{", 0) != 0) continue;
    EXPECT_LE(name.size(), std::string("mapd_ack_latency_seconds_bucket{le=\"0.025\"}").size())
        << name;
  }
  EXPECT_EQ(values["mapd_build_info{version=\"" MAPD_VERSION_FOR_TESTS "\"}"], 1);
  EXPECT_GT(values["process_resident_memory_bytes"], 1e6);
  EXPECT_GT(values["process_open_fds"], 3);
  EXPECT_GT(values["process_start_time_seconds"], 1.7e9);
  EXPECT_EQ(values["mapd_ingest_batches_total"], 6);
  EXPECT_EQ(values["mapd_ack_latency_seconds_count"], 6);
  EXPECT_EQ(values["mapd_ack_latency_seconds_bucket{le=\"+Inf\"}"], 6);
  EXPECT_GT(values["mapd_db_size_bytes"], 0);
  EXPECT_EQ(values["mapd_merges{state=\"proposed\"}"], 0);
  EXPECT_EQ(values["mapd_watchers"], 0);
}

// Prometheus's own checker (Debian's prometheus package, which the test
// command installs) accepts the exposition: syntax and its lint rules.
TEST_F(WebFixture, PromtoolChecksTheMetrics) {
  constexpr const char* kPromtool = "/usr/bin/promtool";
  if (access(kPromtool, X_OK) != 0) GTEST_SKIP() << "no " << kPromtool << " (Debian: prometheus)";
  Start();
  Ingest(RoomBatches("r1", 6));
  httplib::Result r = Client().Get("/metrics");
  ASSERT_TRUE(r);
  const mapd::testing::CommandResult check =
      mapd::testing::RunCommand({kPromtool, "check", "metrics"}, r->body);
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err << "\n" << r->body;
}

// The value of the sample `name{labels}` in a /metrics text, or -1.
double MetricValue(const std::string& text, const std::string& sample) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(sample + " ", 0) == 0) return std::stod(line.substr(sample.size() + 1));
  }
  return -1;
}

// Calls are counted by method and code and timed (go-grpc-prometheus names);
// a batch refused inside a stream that ends OK counts as a rejected batch.
TEST_F(WebFixture, MetricsCountCallsByCodeAndRejectedBatches) {
  Start();
  const auto metrics = [this] { return Client().Get("/metrics")->body; };
  const std::string ingest_ok =
      "grpc_server_handled_total{grpc_service=\"mapserver.v1.MapService\","
      "grpc_method=\"Ingest\",grpc_code=\"OK\"}";
  const std::string rejected = "mapd_ingest_batches_rejected_total{grpc_code=\"INVALID_ARGUMENT\"}";
  const std::string not_found =
      "grpc_server_handled_total{grpc_service=\"mapserver.v1.MapService\","
      "grpc_method=\"DeleteSubmap\",grpc_code=\"NOT_FOUND\"}";
  const std::string before = metrics();
  const double ingests = std::max(0.0, MetricValue(before, ingest_ok));
  const double rejections = std::max(0.0, MetricValue(before, rejected));
  const double misses = std::max(0.0, MetricValue(before, not_found));

  Ingest(RoomBatches("r1", 3));
  {  // one bad batch (no robot id) in an otherwise good stream
    grpc::ClientContext ctx;
    auto stream = stub_->Ingest(&ctx);
    pb::ObservationBatch bad = RoomBatches("r1", 1).front();
    bad.clear_robot_id();
    ASSERT_TRUE(stream->Write(bad));
    stream->WritesDone();
    pb::IngestAck ack;
    while (stream->Read(&ack)) EXPECT_EQ(ack.result(), pb::IngestAck::REJECTED);
    ASSERT_TRUE(stream->Finish().ok());
  }
  {
    grpc::ClientContext ctx;
    pb::DeleteSubmapRequest request;
    request.set_id(12345);
    pb::DeleteSubmapResponse response;
    EXPECT_EQ(stub_->DeleteSubmap(&ctx, request, &response).error_code(),
              grpc::StatusCode::NOT_FOUND);
  }
  const std::string after = metrics();
  EXPECT_EQ(MetricValue(after, ingest_ok), ingests + 2) << after;
  EXPECT_EQ(MetricValue(after, rejected), rejections + 1) << after;
  EXPECT_EQ(MetricValue(after, not_found), misses + 1) << after;
  EXPECT_GE(
      MetricValue(after,
                  "grpc_server_handling_seconds_count{grpc_service=\"mapserver.v1.MapService\","
                  "grpc_method=\"Ingest\"}"),
      ingests + 2);
  EXPECT_NE(after.find("# TYPE mapd_merge_duration_seconds histogram"), std::string::npos);
  EXPECT_NE(after.find("# TYPE mapd_submap_uploads_refused_total counter"), std::string::npos);
}

// A proposed merge recorded directly (proposals need the voxel library).
int64_t RecordProposal(service::Core* core) {
  int64_t id = 0;
  const Status s = core->ExecuteWrite([&](storage::WriteTransaction* txn) {
    StatusOr<storage::MergeIds> ids = txn->RecordMerge(ProposedMerge());
    if (ids.ok()) id = ids->merge_id;
    return ids.status();
  });
  EXPECT_TRUE(s.ok()) << s.ToString();
  return id;
}

httplib::Result Post(httplib::Client c, const std::string& path, const std::string& body,
                     const std::string& token = "") {
  httplib::Headers headers;
  if (!token.empty()) headers.emplace("Authorization", "Bearer " + token);
  return c.Post(path.c_str(), headers, body, "application/json");
}

TEST_F(WebFixture, MergesAreListedAndDecidedOnlyWhenProposed) {
  Start();
  const int64_t id = RecordProposal(server_->core());
  json doc = GetJson("/api/merges?state=proposed");
  ASSERT_EQ(doc["merges"].size(), 1u);
  EXPECT_EQ(doc["merges"][0]["id"], id);
  EXPECT_EQ(doc["merges"][0]["state"], "proposed");
  // The evidence a reviewer decides by (the page's evidence column).
  const json& placed = doc["merges"][0]["inputs"][1];
  EXPECT_EQ(placed["source"], "correlation yaw 58.6 deg, peak 1");
  EXPECT_EQ(placed["restart_spread_voxels"], 2.5);
  EXPECT_EQ(placed["second_residual_m"], -1);  // not measured
  EXPECT_EQ(doc["merges"][0]["inputs"][0]["source"], "");
  const std::string base = "/api/merges/" + std::to_string(id);

  httplib::Result r = Post(Client(), base + "/reject", "{}");
  EXPECT_EQ(r->status, 400);
  EXPECT_THAT(r->body, HasSubstr("reason: required"));
  r = Post(Client(), base + "/reject", R"({"reason": "walls do not line up"})");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["state"], "rejected");
  EXPECT_EQ(json::parse(r->body)["reason"], "walls do not line up");

  r = Post(Client(), base + "/approve", "");
  EXPECT_EQ(r->status, 409);
  EXPECT_THAT(r->body, HasSubstr("is rejected; only a proposed merge can be approved"));
  EXPECT_EQ(GetJson("/api/merges?state=proposed")["merges"].size(), 0u);
}

TEST_F(WebFixture, RequestsAnotherSiteCouldForgeAreRefused) {
  Start();
  const int64_t id = RecordProposal(server_->core());
  const std::string approve = "/api/merges/" + std::to_string(id) + "/approve";
  // A cross-site form: not JSON.
  httplib::Result r = Client().Post(approve.c_str(), "x=1", "application/x-www-form-urlencoded");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400);
  EXPECT_THAT(r->body, HasSubstr("Content-Type: application/json"));
  // A name rebound to 127.0.0.1 (DNS rebinding): its Host is not loopback.
  httplib::Headers rebound = {{"Host", "evil.example:80"}};
  r = Client().Get("/api/features", rebound);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 403);
  EXPECT_THAT(r->body, HasSubstr("evil.example"));
  EXPECT_EQ(GetJson("/api/merges?state=proposed")["merges"].size(), 1u);  // still proposed
}

// The check follows the bound address, however it is spelled (issue 43:
// 127.1 turned it off and a foreign Host reached the approve handler).
TEST_F(WebFixture, AnyLoopbackSpellingOfTheAddressKeepsTheHostCheck) {
  web_address_ = "127.1";
  Start();
  const int64_t id = RecordProposal(server_->core());
  const std::string approve = "/api/merges/" + std::to_string(id) + "/approve";
  httplib::Headers rebound = {{"Host", "evil.example"}};
  httplib::Result r = Client().Post(approve.c_str(), rebound, "{}", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 403);
  EXPECT_THAT(r->body, HasSubstr("not this loopback web view"));
  EXPECT_EQ(GetJson("/api/merges?state=proposed")["merges"].size(), 1u);  // still proposed
  // The operator's own spellings of the address pass.
  for (const std::string host : {"127.1", "127.0.0.1", "localhost", "[::1]"}) {
    httplib::Headers own = {{"Host", host + ":" + std::to_string(web_->port())}};
    r = Client().Get("/api/features", own);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << host;
  }
}

// A browser's open page keeps its connection alive between polls. httplib
// 0.11 stops a connection only between requests, so an idle one held mapd's
// stop for the keep-alive timeout (1 s, added to every SIGTERM): now every
// answer says "Connection: close" and the client closes it.
TEST_F(WebFixture, AnIdleKeepAliveConnectionDoesNotHoldTheStop) {
  Start();
  httplib::Client browser = Client();
  browser.set_keep_alive(true);
  httplib::Result r = browser.Get("/api/robots");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Connection"), "close");
  const auto t0 = std::chrono::steady_clock::now();
  web_->Stop();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::milliseconds(500));
}

TEST_F(WebFixture, RefusedTokensAreLogged) {
  Start();
  MakeToken(service::Role::kReader, "dashboard");
  ::testing::internal::CaptureStderr();
  GetJson("/api/features", 401, "mapd_1_notasecret");
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_THAT(log, HasSubstr("event=auth_refused peer=127.0.0.1:"));
  EXPECT_THAT(log, HasSubstr("via=http"));
}

TEST_F(WebFixture, BadMergeRequestsGetAClear4xx) {
  Start();
  httplib::Result r = Post(Client(), "/api/merges/77/approve", "");
  EXPECT_EQ(r->status, 404);
  EXPECT_THAT(json::parse(r->body)["error"].get<std::string>(), HasSubstr("77"));
  r = Post(Client(), "/api/merges/seven/approve", "");
  EXPECT_EQ(r->status, 400);
  EXPECT_THAT(json::parse(r->body)["error"].get<std::string>(),
              HasSubstr("merge id 'seven' is not a positive decimal integer"));
  r = Post(Client(), "/api/merges/-1/reject", R"({"reason": "x"})");
  EXPECT_EQ(r->status, 400);
  const json bad = GetJson("/api/merges?state=maybe", 400);
  EXPECT_THAT(bad["error"].get<std::string>(), HasSubstr("'maybe' is not proposed"));
  EXPECT_EQ(GetJson("/api/global-map.png", 404)["error"],
            "no global map yet (no submap placed in the map frame)");
}

// The global map's picture is mapctl's top view (client/voxel_render.h): a
// PNG of the stored global map, its version in a header.
TEST_F(WebFixture, TheGlobalMapIsDrawnByTheSharedRenderer) {
  Start();
  storage::GlobalMapRecord global;
  global.version = 3;
  global.resolution_m = 0.1;
  global.data = RoomSubmap(RoomScene(), 0.0, 6.0, Eigen::Isometry3d::Identity());
  global.members.push_back({1, geometry::Rigid3()});
  ASSERT_TRUE(
      server_->core()
          ->ExecuteWrite([&](storage::WriteTransaction* txn) { return txn->PutGlobalMap(global); })
          .ok());
  const httplib::Result r = Client().Get("/api/global-map.png");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(r->get_header_value("X-Global-Map-Version"), "3");
  ASSERT_GT(r->body.size(), 24U);
  EXPECT_EQ(r->body.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // Width and height (PNG IHDR, big-endian): a map of 6 m at 0.1 m is
  // magnified to at least 512 px (RenderOptions::min_map_px), plus the legend.
  const auto be32 = [&](std::size_t at) {
    return static_cast<uint32_t>(static_cast<unsigned char>(r->body[at])) << 24 |
           static_cast<uint32_t>(static_cast<unsigned char>(r->body[at + 1])) << 16 |
           static_cast<uint32_t>(static_cast<unsigned char>(r->body[at + 2])) << 8 |
           static_cast<uint32_t>(static_cast<unsigned char>(r->body[at + 3]));
  };
  EXPECT_GE(std::max(be32(16), be32(20)), 512U);
}

TEST_F(WebFixture, WithTokensReadsNeedAReaderAndDecisionsAnOperator) {
  Start();
  const int64_t id = RecordProposal(server_->core());
  const std::string reader = MakeToken(service::Role::kReader, "dashboard");
  const std::string op = MakeToken(service::Role::kOperator, "alice");
  const std::string reject = "/api/merges/" + std::to_string(id) + "/reject";
  const std::string reason = R"({"reason": "wrong floor"})";

  EXPECT_THAT(GetJson("/api/features", 401)["error"].get<std::string>(),
              HasSubstr("Authorization: Bearer"));
  EXPECT_EQ(Client().Get("/metrics")->status, 401);
  EXPECT_EQ(Client().Get("/")->status, 200);  // the page holds no data
  GetJson("/api/features", 200, reader);
  GetJson("/api/events?since=bad", 400, reader);  // admitted, then the request is checked
  EXPECT_EQ(GetJson("/api/robots", 401, "1.forged")["code"], "UNAUTHENTICATED");

  httplib::Result r = Post(Client(), reject, reason);
  EXPECT_EQ(r->status, 401);
  r = Post(Client(), reject, reason, reader);
  EXPECT_EQ(r->status, 403);
  EXPECT_THAT(r->body, HasSubstr("operator, admin"));
  r = Post(Client(), reject, reason, op);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(json::parse(r->body)["decided_by"], "alice");
}

TEST_F(WebFixture, AnOpenEventStreamDoesNotHoldUpTheStop) {
  Start();
  SseClient events(web_->port(), {});
  ASSERT_TRUE(events.Next());
  EXPECT_EQ(Client().Get("/metrics")->status, 200);  // other requests go on beside it
  web_->Stop();  // returns once the stream has ended (within its 250 ms poll)
  EXPECT_FALSE(events.Next(std::chrono::seconds(10)));
}

TEST_F(WebFixture, APortInUseIsAClearStartupError) {
  Start();
  web::WebServerOptions options;
  options.port = web_->port();
  auto second = web::WebServer::Start(server_->core(), options);
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), StatusCode::kUnavailable);
  EXPECT_THAT(second.status().message(), HasSubstr("http.port " + std::to_string(web_->port()) +
                                                   ": the web view cannot listen on 127.0.0.1:" +
                                                   std::to_string(web_->port())));
}

}  // namespace
}  // namespace mapd::testing
