// A MapServer serving a --data-dir (several maps), with calls that name
// a map: for the tests of maps, and of deleting and restoring them.
#ifndef MAPD_TESTS_SERVICE_SUPPORT_MAPS_FIXTURE_H_
#define MAPD_TESTS_SERVICE_SUPPORT_MAPS_FIXTURE_H_

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "server_fixture.h"

namespace mapd::testing {

class MapsFixture : public ServerFixture {
 protected:
  void SetUp() override {
    Configure();
    UseDataDir();
    StartServer();
  }

  grpc::Status CreateMap(const std::string& id, pb::MapInfo* info = nullptr) {
    grpc::ClientContext ctx;
    pb::CreateMapRequest request;
    request.set_map_id(id);
    pb::MapInfo ignored;
    return stub_->CreateMap(&ctx, request, info ? info : &ignored);
  }

  pb::ListMapsResponse ListMaps() {
    grpc::ClientContext ctx;
    pb::ListMapsResponse maps;
    const grpc::Status s = stub_->ListMaps(&ctx, {}, &maps);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return maps;
  }

  // One Ingest stream opened for `map` (metadata); every ack.
  std::vector<pb::IngestAck> StreamTo(const std::string& map,
                                      const std::vector<pb::ObservationBatch>& batches,
                                      grpc::Status* end = nullptr) {
    grpc::ClientContext ctx;
    ctx.AddMetadata("mapd-map-id", map);
    auto stream = stub_->Ingest(&ctx);
    for (const auto& b : batches) stream->Write(b);
    stream->WritesDone();
    std::vector<pb::IngestAck> acks;
    pb::IngestAck ack;
    while (stream->Read(&ack)) acks.push_back(ack);
    const grpc::Status s = stream->Finish();
    if (end != nullptr) *end = s;
    return acks;
  }

  std::vector<pb::FusedFeature> FeaturesOf(const std::string& map) {
    pb::FeatureMapRequest request;
    request.set_map_id(map);
    request.set_max_wait_ms(5000);
    return Features(request);
  }

  uint64_t StoredBatches(const std::string& map) {
    grpc::ClientContext ctx;
    pb::GetStatsRequest request;
    request.set_map_id(map);
    pb::Stats stats;
    EXPECT_TRUE(stub_->GetStats(&ctx, request, &stats).ok());
    return stats.batches();
  }
};

}  // namespace mapd::testing

#endif  // MAPD_TESTS_SERVICE_SUPPORT_MAPS_FIXTURE_H_
