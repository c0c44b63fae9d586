// Limits that hold under floods (config.h StreamLimits, SubmapOptions): a
// flood of stream opens/cancels and idle uploads leaves health and a normal
// robot answering with nothing lost; the server-wide stream cap, idle upload
// expiry, and a malformed Ingest message (INVALID_ARGUMENT naming its index).
// No timing thresholds: only generous deadlines.
#include <gmock/gmock.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include <chrono>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "common/health.h"
#include "server_fixture.h"

namespace mapd::testing {
namespace {

using ::testing::HasSubstr;

std::chrono::system_clock::time_point In(double seconds) {
  return std::chrono::system_clock::now() +
         std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
}

grpc::ByteBuffer Serialized(const std::string& bytes) {
  grpc::Slice slice(bytes);
  return grpc::ByteBuffer(&slice, 1);
}

class LimitsTest : public ServerFixture {
 protected:
  void SetUp() override {
    config_.streams.max_streams = 64;
    config_.submaps.max_concurrent_uploads = 2;
    config_.submaps.upload_idle_timeout_s = 1.0;
    ServerFixture::SetUp();
  }
};

TEST_F(LimitsTest, FloodOfStreamOpensLeavesHealthAndARobotAnswering) {
  // The normal robot opens its stream before the flood and keeps it.
  grpc::ClientContext robot_ctx;
  robot_ctx.set_deadline(In(120));
  auto robot = stub_->Ingest(&robot_ctx);
  const std::vector<pb::ObservationBatch> batches = Walk("robot", 60);

  // The flood: 20,000 Ingest streams opened and cancelled at once from 4
  // threads on 4 connections, and idle UploadSubmap streams. The server's log
  // (stderr) tells what it made of them.
  ::testing::internal::CaptureStderr();
  std::vector<std::thread> flood;
  for (int t = 0; t < 4; ++t) {
    flood.emplace_back([&, t] {
      grpc::ChannelArguments args;
      args.SetInt("mapd.test.connection", t);  // a connection of its own
      auto channel =
          grpc::CreateCustomChannel(server_->address(), grpc::InsecureChannelCredentials(), args);
      auto stub = pb::MapService::NewStub(channel);
      for (int i = 0; i < 5000; ++i) {
        grpc::ClientContext ctx;
        ctx.set_deadline(In(30));
        auto stream = stub->Ingest(&ctx);
        ctx.TryCancel();
        stream->Finish();
      }
    });
  }
  std::vector<std::unique_ptr<grpc::ClientContext>> upload_ctx;
  std::vector<pb::SubmapInfo> upload_info(20);
  std::vector<std::unique_ptr<grpc::ClientWriter<pb::UploadSubmapRequest>>> uploads;
  for (int i = 0; i < 20; ++i) {
    upload_ctx.push_back(std::make_unique<grpc::ClientContext>());
    upload_ctx.back()->set_deadline(In(60));
    uploads.push_back(stub_->UploadSubmap(upload_ctx.back().get(), &upload_info[i]));
  }

  // Meanwhile the robot streams and health is asked.
  for (const auto& b : batches) ASSERT_TRUE(robot->Write(b));
  EXPECT_TRUE(CheckHealth(channel_, std::chrono::seconds(30)) == Health::kServing);
  for (auto& t : flood) t.join();
  // The flood reached the server and its stream limits refused some of it:
  // 20,000 opens from one address in a few seconds is far beyond
  // limits.stream_opens_per_s (200 a second, a burst of 400), and opens come
  // faster than cancelled streams wind down, beyond limits.max_streams (64
  // here). Each refusal is logged (up to limits.log_lines_per_s lines).
  // The server may still be working through the flood when the clients are
  // done (under CI load its refusals were logged a second after the joins):
  // look again for up to 20 s.
  const std::regex refusal(
      "event=stream_refused rpc=Ingest .*"
      "limits\\.(max_streams|stream_opens_per_s)");
  std::string log = ::testing::internal::GetCapturedStderr();
  for (int i = 0; i < 200 && !std::regex_search(log, refusal); ++i) {
    ::testing::internal::CaptureStderr();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    log += ::testing::internal::GetCapturedStderr();
  }
  EXPECT_TRUE(std::regex_search(log, refusal)) << log.substr(0, 2000);
  robot->WritesDone();
  std::vector<pb::IngestAck> acks;
  pb::IngestAck ack;
  while (robot->Read(&ack)) acks.push_back(ack);
  const grpc::Status robot_status = robot->Finish();
  ASSERT_TRUE(robot_status.ok()) << robot_status.error_message();
  ASSERT_EQ(acks.size(), batches.size());
  for (const auto& a : acks) EXPECT_EQ(a.result(), pb::IngestAck::STORED) << a.message();

  // Idle uploads: every one ends, refused at once (RESOURCE_EXHAUSTED: more
  // than limits.max_concurrent_uploads at a time, or the stream limits) or
  // ended by the idle timeout; none is stored. How many of each depends on
  // how fast the server took the opens beside the flood: an admitted upload
  // idles out after a second and frees its place (a loaded run saw 16
  // refused, not 18). Only 2 places for 20 uploads opened back to back:
  // some are refused unless the opens took over 9 idle timeouts.
  int refused = 0, expired = 0;
  for (auto& u : uploads) {
    const grpc::Status s = u->Finish();
    if (s.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED ||
        s.error_code() == grpc::StatusCode::UNIMPLEMENTED) {
      ++refused;
    } else if (s.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED &&
               s.error_message().find("limits.upload_idle_timeout_s") != std::string::npos) {
      ++expired;
    } else {
      ADD_FAILURE() << "an idle upload ended with " << s.error_code() << ": " << s.error_message();
    }
  }
  EXPECT_EQ(refused + expired, 20);
  EXPECT_GT(refused, 0);
  EXPECT_EQ(Stats().submaps(), 0u);

  // Afterwards: health, reads and a new robot stream all work; nothing lost.
  EXPECT_TRUE(CheckHealth(channel_, std::chrono::seconds(30)) == Health::kServing);
  EXPECT_EQ(Stats().batches(), batches.size());
  // A new robot stream is admitted once the flood's streams are wound down
  // (gRPC may still be working through them: retried, generous deadline).
  std::vector<pb::IngestAck> more;
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  grpc::Status s;
  do {
    more.clear();
    grpc::ClientContext ctx;
    ctx.set_deadline(In(30));
    auto stream = stub_->Ingest(&ctx);
    for (const auto& b : Walk("robot2", 5)) stream->Write(b);
    stream->WritesDone();
    pb::IngestAck a;
    while (stream->Read(&a)) more.push_back(a);
    s = stream->Finish();
    if (!s.ok()) std::this_thread::sleep_for(std::chrono::milliseconds(200));
  } while (!s.ok() && std::chrono::steady_clock::now() < until);
  ASSERT_TRUE(s.ok()) << s.error_message();
  ASSERT_EQ(more.size(), 5u);
  for (const auto& a : more) EXPECT_EQ(a.result(), pb::IngestAck::STORED);
  Features();
  EXPECT_TRUE(last_status_.ok()) << last_status_.error_message();
}

TEST_F(LimitsTest, StreamsBeyondTheServerWideCapAreRefusedAtOnce) {
  std::vector<std::unique_ptr<grpc::ClientContext>> ctx;
  std::vector<std::unique_ptr<grpc::ClientReaderWriter<pb::ObservationBatch, pb::IngestAck>>>
      streams;
  // Opening is asynchronous: a Write completes once the stream is admitted.
  for (size_t i = 0; i < config_.streams.max_streams; ++i) {
    ctx.push_back(std::make_unique<grpc::ClientContext>());
    ctx.back()->set_deadline(In(60));
    streams.push_back(stub_->Ingest(ctx.back().get()));
    ASSERT_TRUE(streams.back()->Write(Walk("r" + std::to_string(i), 1)[0]));
    pb::IngestAck ack;
    ASSERT_TRUE(streams.back()->Read(&ack));
  }
  grpc::ClientContext extra_ctx;
  extra_ctx.set_deadline(In(30));
  auto extra = stub_->Ingest(&extra_ctx);
  pb::IngestAck ack;
  EXPECT_FALSE(extra->Read(&ack));
  const grpc::Status s = extra->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(s.error_message(), HasSubstr("limits.max_streams"));
  for (auto& st : streams) {
    st->WritesDone();
    while (st->Read(&ack)) {
    }
    EXPECT_TRUE(st->Finish().ok());
  }
  // The places are given back.
  EXPECT_EQ(Stream(Walk("after", 2)).size(), 2u);
}

TEST_F(LimitsTest, IdleUploadIsEnded) {
  grpc::ClientContext ctx;
  ctx.set_deadline(In(60));
  pb::SubmapInfo info;
  auto upload = stub_->UploadSubmap(&ctx, &info);
  pb::UploadSubmapRequest header;
  header.mutable_header()->set_robot_id("r1");
  header.mutable_header()->set_name("idle");
  header.mutable_header()->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
  upload->Write(header);
  // ... and nothing more: ended after limits.upload_idle_timeout_s.
  const grpc::Status s = upload->Finish();
  EXPECT_EQ(s.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << s.error_message();
  EXPECT_THAT(s.error_message(), HasSubstr("limits.upload_idle_timeout_s"));
}

TEST_F(LimitsTest, MalformedIngestMessageEndsTheStreamWithInvalidArgument) {
  // A raw stream: a valid batch, then bytes that are no ObservationBatch.
  grpc::GenericStub generic(channel_);
  grpc::ClientContext ctx;
  ctx.set_deadline(In(60));
  grpc::CompletionQueue cq;
  auto call = generic.PrepareCall(&ctx, "/mapserver.v1.MapService/Ingest", &cq);
  auto wait = [&cq](intptr_t want) {
    void* tag = nullptr;
    bool ok = false;
    EXPECT_TRUE(cq.Next(&tag, &ok));
    EXPECT_EQ(reinterpret_cast<intptr_t>(tag), want);
    return ok;
  };
  call->StartCall(reinterpret_cast<void*>(1));
  ASSERT_TRUE(wait(1));
  const pb::ObservationBatch good = Walk("r1", 1)[0];
  call->Write(Serialized(good.SerializeAsString()), reinterpret_cast<void*>(2));
  ASSERT_TRUE(wait(2));
  // Field 1 (robot_id) claims 5 bytes, 2 follow: truncated.
  call->Write(Serialized(std::string("\x0a\x05"
                                     "ab",
                                     4)),
              reinterpret_cast<void*>(3));
  wait(3);
  call->WritesDone(reinterpret_cast<void*>(4));
  wait(4);
  std::vector<pb::IngestAck> acks;
  for (;;) {
    grpc::ByteBuffer buffer;
    call->Read(&buffer, reinterpret_cast<void*>(5));
    if (!wait(5)) break;
    pb::IngestAck ack;
    std::vector<grpc::Slice> slices;
    ASSERT_TRUE(buffer.Dump(&slices).ok());
    std::string bytes;
    for (const auto& sl : slices)
      bytes.append(reinterpret_cast<const char*>(sl.begin()), sl.size());
    ASSERT_TRUE(ack.ParseFromString(bytes));
    acks.push_back(ack);
  }
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(6));
  wait(6);
  ASSERT_EQ(acks.size(), 1u);  // the good batch before it is acknowledged
  EXPECT_EQ(acks[0].result(), pb::IngestAck::STORED);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(status.error_message(), HasSubstr("message 1 "));
  EXPECT_THAT(status.error_message(), HasSubstr("not a valid ObservationBatch"));
  // The server goes on.
  EXPECT_EQ(Stream(Walk("r2", 2)).size(), 2u);
}

}  // namespace
}  // namespace mapd::testing
