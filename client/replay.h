// mapctl replay's recordings: what one recorded robot sends, made before
// anything is sent (commands_replay.cc), from a CARMEN log or, with the
// robot library's plane extractor, from a folder of 3D scans and their poses
// (replay_clouds.cc).
#ifndef MAPD_CLIENT_REPLAY_H_
#define MAPD_CLIENT_REPLAY_H_

#include <grpcpp/grpcpp.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "client/robot/robot_client.h"
#include "mapserver/v1/map_service.pb.h"

namespace mapd::client {

struct ReplayOptions {
  std::vector<std::string> sources;  // CARMEN logs and scan folders, one robot each
  std::vector<std::string> poses;    // the scan folders' pose files, in order
  std::string poses_format = "auto";
  bool wrap_columns = false;  // organised scans: a 360 degree LiDAR's columns
  double max_dt_s = 0.05;     // TUM: the largest scan-to-pose time difference
  std::string robot_id;       // empty: each source's file name
  std::string session;        // empty: replay-<UTC time>
  double rate = 0;            // 0: as fast as possible; 1: as recorded; N: N times as fast
  double max_range_m = 80;
  uint64_t every = 1;       // every Nth scan
  std::string export_path;  // write JSON lines instead of streaming; - for stdout
};

// One source's robot: its batches, made before anything is sent.
struct Recording {
  std::string path;
  std::string robot_id;
  std::vector<mapserver::v1::ObservationBatch> batches;
  std::vector<double> stamps_s;
  std::size_t lines = 0;
  std::size_t planes = 0;
  std::size_t skipped = 0;  // scans without a pose
  robot::IngestCounts counts;
  std::vector<robot::Rejection> rejections;
  grpc::Status status;
};

// Reads the scan folder r->path and its poses file and makes every batch:
// planes of each scan (robot::ExtractPlanes) from its pose. A bad file, pose
// or scan is reported here. kContinue, or the exit code.
int RecordCloudFolder(const ReplayOptions& flags, const std::string& session,
                      const std::string& poses_path, Recording* r);

}  // namespace mapd::client

#endif  // MAPD_CLIENT_REPLAY_H_
