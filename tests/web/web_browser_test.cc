// The page in a real headless Chromium against a real mapd process: the
// ingested walls are drawn (SVG lines with data-id), once without the event
// stream (?live=0) and, after a wall is ingested, with it (the stream's
// resync replaces what the page drew; changes on an open stream are checked
// in web_server_test), and a proposed merge in the merge table with its
// evidence and decision buttons. Skipped with a message when Chromium is not installed
// (Debian: apt-get install chromium; deploy/install-deps.sh installs it).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <regex>
#include <set>

#include "common/process.h"
#include "storage/sqlite/store.h"
#include "web/web_fixture.h"

namespace mapd::testing {
namespace {

std::string FindChromium() {
  if (const char* env = std::getenv("MAPD_CHROMIUM")) return env;
  for (const char* p :
       {"/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/bin/google-chrome"}) {
    if (access(p, X_OK) == 0) return p;
  }
  return "";
}

// A port nothing listens on now (the kernel's choice; mapd binds it a moment later).
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  close(fd);
  return ntohs(a.sin_port);
}

std::set<std::string> DataIds(const std::string& dom) {
  std::set<std::string> ids;
  const std::regex line(R"re(<line [^>]*data-id="(\d+)")re");
  for (std::sregex_iterator it(dom.begin(), dom.end(), line), end; it != end; ++it)
    ids.insert((*it)[1]);
  return ids;
}

class WebBrowserTest : public ::testing::Test {
 protected:
  void SetUp() override {
    chromium_ = FindChromium();
    if (chromium_.empty())
      GTEST_SKIP() << "chromium is not installed (apt-get install chromium, or set MAPD_CHROMIUM): "
                      "the browser test is skipped";
    port_ = FreePort();
  }
  // mapd on the test's database, with the web view on port_.
  void Start() {
    mapd_ = StartMapd(dir_.File("map.db"), {"--http.port", std::to_string(port_)});
    ASSERT_NE(mapd_.port, 0) << mapd_.log();
    stub_ = pb::MapService::NewStub(
        grpc::CreateChannel(mapd_.address, grpc::InsecureChannelCredentials()));
  }
  void TearDown() override {
    if (mapd_.pid > 0) {
      EXPECT_EQ(Stop(mapd_.pid), 0) << mapd_.log();
    }
  }

  void Ingest(const std::vector<pb::ObservationBatch>& batches) {
    grpc::ClientContext ctx;
    auto stream = stub_->Ingest(&ctx);
    for (const auto& b : batches) ASSERT_TRUE(stream->Write(b));
    stream->WritesDone();
    pb::IngestAck ack;
    while (stream->Read(&ack)) ASSERT_EQ(ack.result(), pb::IngestAck::STORED) << ack.message();
    ASSERT_TRUE(stream->Finish().ok());
  }

  std::set<std::string> FeatureIds() {
    httplib::Client c("127.0.0.1", port_);
    httplib::Result r = c.Get("/api/features");
    EXPECT_TRUE(r && r->status == 200);
    std::set<std::string> ids;
    if (!r) return ids;
    const json doc = json::parse(r->body);
    for (const json& f : doc["features"]) ids.insert(std::to_string(f["id"].get<uint64_t>()));
    return ids;
  }

  // The page's DOM once its script has run for `budget_ms` of virtual time.
  std::string DumpDom(const std::string& query, int budget_ms = 3000) {
    const CommandResult r =
        RunCommand({chromium_, "--headless", "--disable-gpu", "--no-sandbox", "--no-first-run",
                    "--user-data-dir=" + dir_.File("chromium"),
                    "--virtual-time-budget=" + std::to_string(budget_ms), "--dump-dom",
                    "http://127.0.0.1:" + std::to_string(port_) + "/" + query},
                   "", std::chrono::seconds(90));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.out;
  }

  TempDir dir_;
  std::string chromium_;
  int port_ = 0;
  MapdProcess mapd_;
  std::unique_ptr<pb::MapService::Stub> stub_;
};

TEST_F(WebBrowserTest, ThePageDrawsTheFusedMapAndItsUpdates) {
  Start();
  Ingest(RoomBatches("r1", 8));
  const std::set<std::string> room = FeatureIds();
  ASSERT_EQ(room.size(), 4u);
  const std::string dom = DumpDom("?live=0");
  EXPECT_EQ(DataIds(dom), room) << dom.substr(0, 4000);
  EXPECT_THAT(dom, ::testing::HasSubstr("data-robot=\"r1\""));

  Ingest(FarWallBatches("r2", 4));
  const std::set<std::string> all = FeatureIds();
  ASSERT_EQ(all.size(), 5u);
  // Live (the default): the page also opens the event stream, whose resync
  // replaces what it drew; the status line says so.
  const std::string live = DumpDom("");
  EXPECT_EQ(DataIds(live), all);
  EXPECT_THAT(live, ::testing::HasSubstr("5 features · 0 planes · live"));
}

// A proposed merge is listed with the evidence a reviewer decides by and the
// buttons to decide it (recorded in the database before mapd opens it).
TEST_F(WebBrowserTest, TheMergeTableShowsEachPlacementsEvidence) {
  {
    auto store = storage::SqliteStore::Open(dir_.File("map.db"), storage::StoreOptions{});
    ASSERT_TRUE(store.ok()) << store.status().ToString();
    auto txn = (*store)->BeginWrite();
    ASSERT_TRUE(txn.ok()) << txn.status().ToString();
    ASSERT_TRUE((*txn)->RecordMerge(ProposedMerge()).ok());
    ASSERT_TRUE((*txn)->Commit().ok());
  }
  Start();
  const std::string dom = DumpDom("?live=0");
  EXPECT_THAT(dom, ::testing::HasSubstr(
                       "submap 2: correlation yaw 58.6 deg, peak 1, residual 0.040 m, overlap "
                       "0.99, restart spread 2.50 vox, runner-up -"))
      << dom.substr(0, 4000);
  EXPECT_THAT(dom, ::testing::HasSubstr("<button>approve</button>"));
}

// mapd itself (no browser needed): a taken http.port stops it at start with
// the port named, after closing its database cleanly.
TEST(MapdWebPort, APortInUseIsAClearStartupError) {
  TempDir dir;
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(listen(fd, 1), 0);
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  const std::string port = std::to_string(ntohs(a.sin_port));
  const CommandResult r = RunCommand({kDefaultMapdBinary, "--db", dir.File("map.db"), "--listen",
                                      "127.0.0.1:0", "--http.port", port});
  close(fd);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, ::testing::HasSubstr("mapd: UNAVAILABLE: http.port " + port +
                                          ": the web view cannot listen on 127.0.0.1:" + port));
  EXPECT_THAT(r.err, ::testing::HasSubstr("event=stopped"));
}

}  // namespace
}  // namespace mapd::testing
