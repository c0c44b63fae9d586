#include "bench/mapd_merge_client.h"

#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "mapserver/v1/map_service.grpc.pb.h"

namespace mapd::bench {
namespace {

namespace pb = mapserver::v1;

constexpr size_t kChunkBytes = size_t{1} << 20;

const char* CodeName(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    default:
      return "OTHER";
  }
}

// utime + stime of a process (all its threads), seconds, and stime alone in
// *system_s; -1 if unreadable.
double ProcessCpuSeconds(int pid, double* system_s) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  *system_s = -1;
  if (pid <= 0 || !std::getline(stat, line)) return -1;
  // Fields after the command name (which may hold spaces) in parentheses.
  std::istringstream rest(line.substr(line.rfind(')') + 2));
  std::string field;
  double ticks = 0, system_ticks = 0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);  // utime, stime
    if (i == 15) system_ticks = std::stod(field);
  }
  const double tick_s = 1.0 / static_cast<double>(sysconf(_SC_CLK_TCK));
  *system_s = system_ticks * tick_s;
  return ticks * tick_s;
}

}  // namespace

struct MapdMergeClient::Stub {
  std::unique_ptr<pb::MapService::Stub> stub;
};

MapdMergeClient::MapdMergeClient(const std::string& address, int mapd_pid)
    : stub_(new Stub), mapd_pid_(mapd_pid) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(64 << 20);
  stub_->stub = pb::MapService::NewStub(
      grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args));
}

MapdMergeClient::~MapdMergeClient() = default;

MapdVerdict MapdMergeClient::Merge(const std::string& name, const std::string& a_bt,
                                   const std::string& b_bt) {
  MapdVerdict v;
  uint64_t ids[2] = {0, 0};
  const std::string robots[2] = {"bench-a", "bench-b"};
  const std::string* files[2] = {&a_bt, &b_bt};
  for (int i = 0; i < 2; ++i) {
    grpc::ClientContext ctx;
    pb::SubmapInfo info;
    auto writer = stub_->stub->UploadSubmap(&ctx, &info);
    pb::UploadSubmapRequest m;
    m.mutable_header()->set_robot_id(robots[i]);
    m.mutable_header()->set_name(name);
    m.mutable_header()->set_format(pb::SUBMAP_FORMAT_OCTOMAP_BT);
    bool open = writer->Write(m);
    for (size_t off = 0; open && off < files[i]->size(); off += kChunkBytes) {
      pb::UploadSubmapRequest chunk;
      chunk.set_chunk(files[i]->substr(off, kChunkBytes));
      open = writer->Write(chunk);
    }
    if (open) writer->WritesDone();
    const grpc::Status s = writer->Finish();
    if (!s.ok()) {
      v.code = CodeName(s.error_code());
      v.message = "upload of " + robots[i] + " refused: " + s.error_message();
      return v;
    }
    ids[i] = info.id();
  }
  // The merge alone, as the library's worker measures it: wait (up to 60 s)
  // until mapd is quiet, its background work done (the global map built
  // after the previous accepted merge and these uploads), and say how long.
  double system_before = 0, system_after = 0;
  const auto quiet_start = std::chrono::steady_clock::now();
  for (double last = ProcessCpuSeconds(mapd_pid_, &system_before);;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const double now = ProcessCpuSeconds(mapd_pid_, &system_before);
    if (now < 0 || now - last < 0.01 ||
        std::chrono::steady_clock::now() - quiet_start > std::chrono::seconds(60)) {
      break;
    }
    last = now;
  }
  v.background_wait_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - quiet_start).count();
  const double cpu_before = ProcessCpuSeconds(mapd_pid_, &system_before);
  const auto wall_start = std::chrono::steady_clock::now();
  grpc::ClientContext ctx;
  pb::MergeSubmapsRequest request;
  request.add_submap_ids(ids[0]);
  request.add_submap_ids(ids[1]);
  auto reader = stub_->stub->MergeSubmaps(&ctx, request);
  pb::MergeProgress p;
  pb::MergeResult result;
  bool has_result = false;
  while (reader->Read(&p)) {
    if (p.has_result()) {
      result = p.result();
      has_result = true;
    }
  }
  const grpc::Status s = reader->Finish();
  v.merge_wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double cpu_after = ProcessCpuSeconds(mapd_pid_, &system_after);
  if (cpu_before >= 0 && cpu_after >= 0) {
    v.mapd_cpu_s = cpu_after - cpu_before;
    v.mapd_system_cpu_s = system_after - system_before;
  }
  v.code = CodeName(s.error_code());
  v.message = s.error_message();
  v.answered = s.ok() || s.error_code() == grpc::StatusCode::FAILED_PRECONDITION;
  v.accepted = s.ok() && has_result && result.state() == pb::MERGE_STATE_ACCEPTED;
  for (const pb::SubmapAlignment& a : result.alignments()) {
    if (a.submap_id() != ids[1]) continue;
    const pb::Rigid3& T = a.t_reference_submap();
    v.T_a_b.linear() =
        Eigen::Quaterniond(T.rotation().w(), T.rotation().x(), T.rotation().y(), T.rotation().z())
            .normalized()
            .toRotationMatrix();
    v.T_a_b.translation() =
        Eigen::Vector3d(T.translation().x(), T.translation().y(), T.translation().z());
  }
  return v;
}

}  // namespace mapd::bench
