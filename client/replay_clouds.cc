// mapctl replay of a folder of 3D scans: every scan's planes through the
// robot library (ReadCloudFile and ExtractPlanes, loaded at run time from
// libmapd_robot_c.so: plane_library.h; FeatureBatch), from the pose a TUM or
// KITTI trajectory gives it.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "client/cli.h"
#include "client/plane_library.h"
#include "client/replay.h"
#include "client/robot/observation_batch.h"
#include "client/robot/pose_files.h"
#include "client/text_util.h"

namespace mapd::client {
namespace {

namespace fs = std::filesystem;

struct ScanFile {
  std::string path;
  double stamp_s = NAN;  // the name as a number (a timestamp, or KITTI's index)
};

// The folder's scans (.pcd, .ply, .bin, .xyz), by name: numerically when every
// name is a number (1305031102.175304.pcd, 000042.bin), else as text.
std::vector<ScanFile> ListScans(const std::string& folder) {
  std::vector<ScanFile> scans;
  std::error_code ec;  // an unreadable folder lists no scan (and says so)
  for (fs::directory_iterator it(folder, ec), last; !ec && it != last; it.increment(ec)) {
    const fs::directory_entry& e = *it;
    if (!e.is_regular_file(ec)) continue;
    std::string ext = e.path().extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".pcd" && ext != ".ply" && ext != ".bin" && ext != ".xyz") continue;
    ScanFile s;
    s.path = e.path().string();
    const std::string stem = e.path().stem().string();
    char* end = nullptr;
    const double v = std::strtod(stem.c_str(), &end);
    if (!stem.empty() && end == stem.c_str() + stem.size() && std::isfinite(v)) {
      s.stamp_s = v;
    }
    scans.push_back(std::move(s));
  }
  const bool numeric = !scans.empty() && std::all_of(scans.begin(), scans.end(), [](const auto& s) {
    return std::isfinite(s.stamp_s);
  });
  std::sort(scans.begin(), scans.end(), [numeric](const ScanFile& a, const ScanFile& b) {
    return numeric ? a.stamp_s < b.stamp_s : a.path < b.path;
  });
  if (!numeric) {
    for (ScanFile& s : scans) s.stamp_s = NAN;
  }
  return scans;
}

// The first of `candidates` that exists, or "".
std::string FirstExisting(std::initializer_list<fs::path> candidates) {
  for (const fs::path& p : candidates) {
    std::error_code ec;
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return "";
}

// KITTI's world is its left camera's at the first scan: x right, y down, z
// forward. mapd's map frame has z up: x forward, y left.
Eigen::Isometry3d KittiWorldToMap() {
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  return T;
}

// Each scan's pose in the map frame and its time; scans without one get a
// NaN stamp. kContinue, or the exit code (the error printed).
int PoseScans(const ReplayOptions& flags, const std::string& folder, const std::string& poses_path,
              const std::vector<ScanFile>& scans, std::vector<Eigen::Isometry3d>* poses,
              std::vector<double>* stamps_s) {
  robot::PoseFormat format = robot::PoseFormat::kAuto;
  if (flags.poses_format == "tum") format = robot::PoseFormat::kTum;
  if (flags.poses_format == "kitti") format = robot::PoseFormat::kKitti;
  auto trajectory = robot::ReadPoseFile(poses_path, format, &format);
  if (!trajectory.ok()) {
    PrintError("replay: " + trajectory.status().message());
    return trajectory.status().code() == StatusCode::kNotFound ? kExitFailed : kExitUsage;
  }
  if (trajectory->empty()) {
    PrintError("replay: " + poses_path + " has no pose");
    return kExitUsage;
  }
  const bool kitti = format == robot::PoseFormat::kKitti;
  poses->assign(scans.size(), Eigen::Isometry3d::Identity());
  stamps_s->assign(scans.size(), NAN);
  if (kitti) {
    // By order, as KITTI numbers them; times.txt and calib.txt's Tr when
    // the odometry layout has them (sequences/NN/{velodyne/, times.txt, calib.txt}).
    if (trajectory->size() != scans.size()) {
      PrintError(Printf("replay: %s has %zu poses for %zu scans in %s (KITTI poses go by order)",
                        poses_path.c_str(), trajectory->size(), scans.size(), folder.c_str()));
      return kExitUsage;
    }
    const fs::path dir(folder);
    const std::string times_path =
        FirstExisting({dir / "times.txt", dir.parent_path() / "times.txt"});
    std::vector<double> times;
    if (!times_path.empty()) {
      auto read = robot::ReadKittiTimes(times_path);
      if (!read.ok() || read->size() != scans.size()) {
        PrintError("replay: " + (read.ok()
                                     ? times_path + " has " + std::to_string(read->size()) +
                                           " times for " + std::to_string(scans.size()) + " scans"
                                     : read.status().message()));
        return kExitUsage;
      }
      times = std::move(read).value();
    }
    Eigen::Isometry3d T_camera_velodyne = Eigen::Isometry3d::Identity();
    const std::string calib = FirstExisting({dir / "calib.txt", dir.parent_path() / "calib.txt"});
    if (!calib.empty()) {
      auto tr = robot::ReadKittiVelodyneToCamera(calib);
      if (!tr.ok()) {
        PrintError("replay: " + tr.status().message());
        return kExitUsage;
      }
      T_camera_velodyne = *tr;
    }
    const Eigen::Isometry3d T_map_world = KittiWorldToMap();
    for (size_t i = 0; i < scans.size(); ++i) {
      (*poses)[i] = T_map_world * (*trajectory)[i].T_world_sensor * T_camera_velodyne;
      (*stamps_s)[i] = times.empty() ? 0.1 * static_cast<double>(i) : times[i];  // 10 Hz
    }
    return kContinue;
  }
  const auto by_order = [&]() -> int {
    if (trajectory->size() != scans.size()) {
      PrintError(
          Printf("replay: %s has %zu poses for %zu scans in %s (scans not named by "
                 "their times go with the poses by order)",
                 poses_path.c_str(), trajectory->size(), scans.size(), folder.c_str()));
      return kExitUsage;
    }
    for (size_t i = 0; i < scans.size(); ++i) {
      (*poses)[i] = (*trajectory)[i].T_world_sensor;
      (*stamps_s)[i] = (*trajectory)[i].stamp_s;
    }
    return kContinue;
  };
  if (!std::isfinite(scans.front().stamp_s)) return by_order();
  // Scans named by their times: the nearest pose in time, within max_dt_s.
  std::vector<robot::StampedPose> sorted = *trajectory;
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return a.stamp_s < b.stamp_s; });
  for (size_t i = 0; i < scans.size(); ++i) {
    const double t = scans[i].stamp_s;
    auto it = std::lower_bound(sorted.begin(), sorted.end(), t,
                               [](const robot::StampedPose& p, double v) { return p.stamp_s < v; });
    const robot::StampedPose* best = nullptr;
    if (it != sorted.end()) best = &*it;
    if (it != sorted.begin() &&
        (best == nullptr || t - std::prev(it)->stamp_s < best->stamp_s - t)) {
      best = &*std::prev(it);
    }
    if (best == nullptr || std::abs(best->stamp_s - t) > flags.max_dt_s) continue;
    (*poses)[i] = best->T_world_sensor;
    (*stamps_s)[i] = t;
  }
  // Numbered, not timed (000000.pcd ...): no name is near a pose's time.
  if (std::none_of(stamps_s->begin(), stamps_s->end(), [](double t) { return std::isfinite(t); })) {
    return by_order();
  }
  return kContinue;
}

}  // namespace

int RecordCloudFolder(const ReplayOptions& flags, const std::string& session,
                      const std::string& poses_path, Recording* r) {
  const std::vector<ScanFile> scans = ListScans(r->path);
  if (scans.empty()) {
    PrintError("replay: " + r->path + " has no scan (.pcd, .ply, .bin or .xyz files)");
    return kExitUsage;
  }
  std::vector<Eigen::Isometry3d> poses;
  std::vector<double> stamps_s;
  if (int rc = PoseScans(flags, r->path, poses_path, scans, &poses, &stamps_s); rc != kContinue) {
    return rc;
  }
  auto library = PlaneLibrary::Load();
  if (!library.ok()) {
    PrintError("replay: " + r->path + " is a folder of 3D scans: " + library.status().message());
    return kExitFailed;
  }
  const bool tty = isatty(STDERR_FILENO) != 0;
  std::size_t posed = 0;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (!std::isfinite(stamps_s[i])) {
      ++r->skipped;
      continue;
    }
    if (posed++ % flags.every != 0) continue;
    if (tty) {
      std::fprintf(stderr, "\rreplay: extracting %s: %zu / %zu scans", r->robot_id.c_str(), i + 1,
                   scans.size());
      std::fflush(stderr);
    }
    auto features = (*library)->PlanesOfFile(scans[i].path, flags.wrap_columns);
    if (!features.ok()) {
      if (tty) std::fprintf(stderr, "\n");
      PrintError("replay: " + features.status().message());
      return features.status().code() == StatusCode::kNotFound ? kExitFailed : kExitUsage;
    }
    robot::BatchHeader header;
    header.robot_id = r->robot_id;
    header.session_id = session;
    header.seq = r->batches.size() + 1;
    header.stamp_ns = static_cast<int64_t>(std::llround(stamps_s[i] * 1e9));
    auto batch = robot::FeatureBatch(header, poses[i], {}, *features);
    if (!batch.ok()) {
      if (tty) std::fprintf(stderr, "\n");
      PrintError("replay: " + scans[i].path + ": " + batch.status().message());
      return kExitUsage;
    }
    r->planes += features->size();
    r->stamps_s.push_back(stamps_s[i]);
    r->batches.push_back(std::move(batch).value());
  }
  if (tty) std::fprintf(stderr, "\n");
  if (r->batches.empty()) {
    PrintError(Printf("replay: no scan of %s has a pose within %.3f s in %s", r->path.c_str(),
                      flags.max_dt_s, poses_path.c_str()));
    return kExitUsage;
  }
  return kContinue;
}

}  // namespace mapd::client
