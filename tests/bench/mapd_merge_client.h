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
};

class MapdMergeClient {
 public:
  explicit MapdMergeClient(const std::string& address);  // "127.0.0.1:PORT"
  ~MapdMergeClient();
  // Uploads a and b under robots "bench-a" / "bench-b" named `name` (unique
  // per call), merges them (a is the reference) and returns the verdict.
  MapdVerdict Merge(const std::string& name, const std::string& a_bt, const std::string& b_bt);

 private:
  struct Stub;
  std::unique_ptr<Stub> stub_;
};

}  // namespace mapd::bench

#endif  // MAPD_TESTS_BENCH_MAPD_MERGE_CLIENT_H_
