// TLS and mutual TLS with certificates made at test time by the openssl CLI
// (skipped without it): a client certificate's CN is a robot id, one from an
// unknown CA is refused, and tokens work over TLS.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include "common/health.h"
#include "common/process.h"
#include "common/temp_dir.h"
#include "service/support/auth_fixture.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

std::string OpensslBinary() {
  for (const char* p : {"/usr/bin/openssl", "/usr/local/bin/openssl", "/bin/openssl"}) {
    if (access(p, X_OK) == 0) return p;
  }
  return "";
}

class TlsAuthTest : public AuthFixture {
 protected:
  void SetUp() override {
    openssl_ = OpensslBinary();
    if (openssl_.empty()) GTEST_SKIP() << "no openssl CLI: cannot make test certificates";
    ASSERT_TRUE(MakeCa("ca") && MakeCa("rogue-ca"));
    std::ofstream(dir_.File("san.ext")) << "subjectAltName=IP:127.0.0.1,DNS:localhost\n";
    ASSERT_TRUE(MakeCert("server", "localhost", "ca", true));
    ASSERT_TRUE(MakeCert("r1", "r1", "ca", false));
    ASSERT_TRUE(MakeCert("rogue", "r1", "rogue-ca", false));
    config_.listen = "127.0.0.1:0";
    config_.db_path = dir_.File("map.db");
    config_.shutdown_grace_s = 1.0;
    config_.busy_timeout_ms = 300;
    config_.tls_cert = dir_.File("server.pem");
    config_.tls_key = dir_.File("server.key");
    if (mutual_) config_.tls_client_ca = dir_.File("ca.pem");
    config_.health_listen = health_listen_;
    StartServer();
  }

  bool Run(std::vector<std::string> args) {
    args.insert(args.begin(), openssl_);
    const CommandResult r = RunCommand(args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0;
  }
  bool MakeCa(const std::string& name) {
    return Run({"req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1",
                "-nodes", "-keyout", dir_.File(name + ".key"), "-out", dir_.File(name + ".pem"),
                "-days", "2", "-subj", "/CN=" + name});
  }
  bool MakeCert(const std::string& name, const std::string& cn, const std::string& ca,
                bool server) {
    if (!Run({"req", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
              "-keyout", dir_.File(name + ".key"), "-out", dir_.File(name + ".csr"), "-subj",
              "/CN=" + cn})) {
      return false;
    }
    std::vector<std::string> sign = {"x509",
                                     "-req",
                                     "-in",
                                     dir_.File(name + ".csr"),
                                     "-CA",
                                     dir_.File(ca + ".pem"),
                                     "-CAkey",
                                     dir_.File(ca + ".key"),
                                     "-CAcreateserial",
                                     "-out",
                                     dir_.File(name + ".pem"),
                                     "-days",
                                     "2"};
    if (server) sign.insert(sign.end(), {"-extfile", dir_.File("san.ext")});
    return Run(sign);
  }

  // A stub over TLS trusting ca.pem, presenting `client` (a name above) if given.
  std::unique_ptr<pb::MapService::Stub> TlsStub(const std::string& client = "") {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = ReadFileBytes(dir_.File("ca.pem"));
    if (!client.empty()) {
      ssl.pem_cert_chain = ReadFileBytes(dir_.File(client + ".pem"));
      ssl.pem_private_key = ReadFileBytes(dir_.File(client + ".key"));
    }
    return pb::MapService::NewStub(
        grpc::CreateChannel(server_->address(), grpc::SslCredentials(ssl)));
  }

  static grpc::Status WhoAmI(pb::MapService::Stub* stub, const std::string& token,
                             pb::WhoAmIResponse* me) {
    auto ctx = As(token);
    ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    return stub->WhoAmI(ctx.get(), {}, me);
  }

  bool mutual_ = false;
  std::string health_listen_;  // config.health_listen
  std::string openssl_;
};

class MutualTlsTest : public TlsAuthTest {
 protected:
  MutualTlsTest() { mutual_ = true; }
};

class MutualTlsHealthPortTest : public TlsAuthTest {
 protected:
  MutualTlsHealthPortTest() {
    mutual_ = true;
    health_listen_ = "127.0.0.1:0";
  }
};

TEST_F(TlsAuthTest, TokensWorkOverTls) {
  const std::string admin = OfflineToken(service::Role::kAdmin, "root");
  auto stub = TlsStub();
  pb::WhoAmIResponse me;
  ASSERT_TRUE(WhoAmI(stub.get(), admin, &me).ok());
  EXPECT_EQ(me.name(), "root");
  EXPECT_EQ(me.role(), pb::ROLE_ADMIN);
  EXPECT_EQ(WhoAmI(stub.get(), "", &me).error_code(), grpc::StatusCode::UNAUTHENTICATED);
}

TEST_F(MutualTlsTest, CertificateCnIsTheRobot) {
  auto stub = TlsStub("r1");
  pb::WhoAmIResponse me;
  const grpc::Status s = WhoAmI(stub.get(), "", &me);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(me.name(), "r1");
  EXPECT_EQ(me.role(), pb::ROLE_ROBOT);
  EXPECT_EQ(me.robot_id(), "r1");
  EXPECT_FALSE(me.anonymous());

  grpc::ClientContext ctx;
  auto stream = stub->Ingest(&ctx);
  std::vector<pb::ObservationBatch> batches = Walk("r1", 2);
  batches.push_back(Walk("r2", 1, 50)[0]);
  for (const auto& b : batches) ASSERT_TRUE(stream->Write(b));
  stream->WritesDone();
  pb::IngestAck ack;
  int stored = 0, denied = 0;
  while (stream->Read(&ack)) {
    stored += ack.result() == pb::IngestAck::STORED;
    denied += ack.code() == grpc::StatusCode::PERMISSION_DENIED;
  }
  EXPECT_TRUE(stream->Finish().ok());
  EXPECT_EQ(stored, 2);
  EXPECT_EQ(denied, 1);
}

TEST_F(MutualTlsTest, TokenOverMutualTlsNamesTheOperator) {
  const std::string admin = OfflineToken(service::Role::kAdmin, "root");
  auto stub = TlsStub("r1");
  pb::WhoAmIResponse me;
  ASSERT_TRUE(WhoAmI(stub.get(), admin, &me).ok());
  EXPECT_EQ(me.name(), "root");
  EXPECT_EQ(me.role(), pb::ROLE_ADMIN);
}

TEST_F(MutualTlsTest, UnknownCaOrNoCertificateIsRefused) {
  pb::WhoAmIResponse me;
  auto rogue = TlsStub("rogue");
  const grpc::Status r = WhoAmI(rogue.get(), "", &me);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.error_code(), grpc::StatusCode::UNAVAILABLE) << r.error_message();
  auto none = TlsStub();
  EXPECT_EQ(WhoAmI(none.get(), "", &me).error_code(), grpc::StatusCode::UNAVAILABLE);
  // Plaintext does not get in either.
  auto plain = pb::MapService::NewStub(
      grpc::CreateChannel(server_->address(), grpc::InsecureChannelCredentials()));
  EXPECT_FALSE(WhoAmI(plain.get(), "", &me).ok());
}

// An orchestrator's probe has no client certificate: the plaintext loopback
// health port answers it, and gives nothing else away (issue 43).
TEST_F(MutualTlsHealthPortTest, HealthAnswersWithoutACertificateAndNothingElseDoes) {
  ASSERT_GT(server_->health_port(), 0);
  const std::string health = "127.0.0.1:" + std::to_string(server_->health_port());
  auto channel = grpc::CreateChannel(health, grpc::InsecureChannelCredentials());
  EXPECT_EQ(CheckHealth(channel, std::chrono::seconds(10)), Health::kServing);
  auto plain = pb::MapService::NewStub(channel);
  pb::WhoAmIResponse me;
  const grpc::Status s = WhoAmI(plain.get(), "", &me);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAUTHENTICATED) << s.error_message();
  // The TLS port still refuses a call without a certificate.
  auto none = TlsStub();
  EXPECT_EQ(WhoAmI(none.get(), "", &me).error_code(), grpc::StatusCode::UNAVAILABLE);
}

}  // namespace
}  // namespace mapd::testing
