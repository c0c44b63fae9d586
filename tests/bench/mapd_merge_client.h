// A crop pair merged through a real mapd, as an operator merges (issue 42
// item 1): both crops uploaded (UploadSubmap), MergeSubmaps, the answer read.
// voxel_merge_bench --mapd runs every "ours" pair through it as well and
// counts where the server and the library decide differently.
#ifndef MAPD_TESTS_BENCH_MAPD_MERGE_CLIENT_H_
#define MAPD_TESTS_BENCH_MAPD_MERGE_CLIENT_H_

#include <Eigen/Geometry>
#include <memory>
#include <string>

namespace mapd::bench {

struct MapdVerdict {
  bool answered = false;  // false: the RPCs failed for another reason (message says)
  bool accepted = false;
  std::string code;     // the gRPC status code's name ("OK", "FAILED_PRECONDITION", ...)
  std::string message;  // the server's reason when refused
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  // b in a's frame, when accepted
  // The MergeSubmaps call alone (not the uploads): wall seconds from the
  // request to the final status, and the CPU seconds mapd used meanwhile
  // (its /proc stat, all threads; -1 without a pid).
  double merge_wall_s = 0;
  double mapd_cpu_s = -1;
  double mapd_system_cpu_s = -1;  // its system part (mostly the kernel zeroing fresh pages)
  // How long mapd took to fall quiet before the merge was sent (its global
  // map build after the previous accepted merge and the uploads).
  double background_wait_s = 0;
};

class MapdMergeClient {
 public:
  // address: "127.0.0.1:PORT"; mapd_pid: the server's process, for its CPU
  // (0: not measured).
  explicit MapdMergeClient(const std::string& address, int mapd_pid = 0);
  ~MapdMergeClient();
  // Uploads a and b under robots "bench-a" / "bench-b" named `name` (unique
  // per call), merges them (a is the reference) and returns the verdict.
  MapdVerdict Merge(const std::string& name, const std::string& a_bt, const std::string& b_bt);

 private:
  struct Stub;
  std::unique_ptr<Stub> stub_;
  int mapd_pid_ = 0;
};

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_MAPD_MERGE_CLIENT_H_
