#include "client/robot/cloud_files.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <string>

namespace mapd::robot {
namespace {

std::string Extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// A PCD header checked before PCL reads the file: PCL 1.13's reader crashes
// on some malformed files (no header at all, data shorter than the header
// says), so those are refused here, naming what is wrong.
Status CheckPcdHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::map<std::string, std::vector<std::string>> keys;
  std::string line;
  for (int n = 0; n < 64 && std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string key, value;
    words >> key;
    std::vector<std::string>& values = keys[key];
    while (words >> value) values.push_back(value);
    if (key == "DATA") break;
  }
  const auto bad = [&](const std::string& what) {
    return Status::InvalidArgument(path + " is not a readable PCD file: " + what);
  };
  for (const char* key : {"FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT", "POINTS", "DATA"}) {
    if (keys.count(key) == 0) return bad(std::string("no ") + key + " line in its header");
  }
  const size_t fields = keys["FIELDS"].size();
  std::vector<std::string> counts = keys["COUNT"];
  if (counts.empty()) counts.assign(fields, "1");
  if (fields == 0 || keys["SIZE"].size() != fields || keys["TYPE"].size() != fields ||
      counts.size() != fields) {
    return bad("FIELDS, SIZE, TYPE and COUNT do not have one entry a field");
  }
  const auto number = [](const std::string& text, uint64_t* out) {
    char* end = nullptr;
    errno = 0;
    const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || errno == ERANGE || text[0] == '-') return false;
    *out = v;
    return true;
  };
  uint64_t point_bytes = 0;
  for (size_t i = 0; i < fields; ++i) {
    uint64_t size = 0, count = 0;
    if (!number(keys["SIZE"][i], &size) || (size != 1 && size != 2 && size != 4 && size != 8) ||
        !number(counts[i], &count) || count < 1 || count > 4096) {
      return bad("field " + keys["FIELDS"][i] + " has a bad SIZE or COUNT");
    }
    point_bytes += size * count;
  }
  uint64_t width = 0, height = 0, points = 0;
  if (keys["WIDTH"].size() != 1 || keys["HEIGHT"].size() != 1 || keys["POINTS"].size() != 1 ||
      !number(keys["WIDTH"][0], &width) || !number(keys["HEIGHT"][0], &height) ||
      !number(keys["POINTS"][0], &points) || points > (1ull << 31) || width * height != points) {
    return bad("WIDTH x HEIGHT is not POINTS (or not numbers)");
  }
  const std::string data = keys["DATA"].empty() ? "" : keys["DATA"][0];
  if (data == "ascii") return Status::Ok();
  if (data != "binary" && data != "binary_compressed") {
    return bad("DATA is '" + data + "', not ascii, binary or binary_compressed");
  }
  const std::streamoff start = in.tellg();
  in.seekg(0, std::ios::end);
  const uint64_t left = start < 0 ? 0 : static_cast<uint64_t>(in.tellg() - start);
  if (data == "binary") {
    if (left < points * point_bytes) {
      return bad(std::to_string(left) + " bytes of data for " + std::to_string(points) +
                 " points of " + std::to_string(point_bytes) + " bytes");
    }
    return Status::Ok();
  }
  uint32_t sizes[2] = {0, 0};  // compressed, uncompressed
  in.seekg(start);
  if (left < sizeof sizes || !in.read(reinterpret_cast<char*>(sizes), sizeof sizes) ||
      sizes[0] > left - sizeof sizes || sizes[1] != points * point_bytes) {
    return bad("its compressed data's sizes do not match the header");
  }
  return Status::Ok();
}

// PCD or PLY through PCL: a PCLPointCloud2 that must have x, y and z.
StatusOr<CloudFile> ReadWithPcl(const std::string& path, bool pcd) {
  if (pcd) MAPD_RETURN_IF_ERROR(CheckPcdHeader(path));
  pcl::PCLPointCloud2 blob;
  // PCL's readers print their own complaint to stderr and return < 0.
  const int rc = pcd ? pcl::io::loadPCDFile(path, blob) : pcl::io::loadPLYFile(path, blob);
  if (rc < 0) {
    return Status::InvalidArgument(path + " is not a readable " + (pcd ? "PCD" : "PLY") + " file");
  }
  for (const char* axis : {"x", "y", "z"}) {
    const bool has = std::any_of(blob.fields.begin(), blob.fields.end(),
                                 [&](const pcl::PCLPointField& f) { return f.name == axis; });
    if (!has) return Status::InvalidArgument(path + " has no '" + axis + "' field");
  }
  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::fromPCLPointCloud2(blob, xyz);
  CloudFile out;
  out.points.reserve(xyz.size());
  for (const pcl::PointXYZ& p : xyz) out.points.emplace_back(p.x, p.y, p.z);
  out.rows = static_cast<int>(std::max<uint32_t>(xyz.height, 1));
  out.columns = static_cast<int>(xyz.width);
  if (static_cast<size_t>(out.rows) * static_cast<size_t>(out.columns) != out.points.size()) {
    out.rows = 1;  // not a grid after all: unorganised
    out.columns = static_cast<int>(out.points.size());
  }
  return out;
}

// "x y z [anything]" a line; blank lines and lines starting with # skipped.
StatusOr<CloudFile> ReadText(const std::string& path) {
  std::ifstream in(path);
  CloudFile out;
  std::string line;
  size_t number = 0;
  while (std::getline(in, line)) {
    ++number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const char* cursor = line.c_str();
    float v[3];
    for (float& x : v) {
      char* end = nullptr;
      errno = 0;
      x = std::strtof(cursor, &end);
      if (end == cursor || errno == ERANGE) {
        return Status::InvalidArgument(path + ":" + std::to_string(number) +
                                       ": not an 'x y z' line");
      }
      cursor = end;
    }
    out.points.emplace_back(v[0], v[1], v[2]);
  }
  if (in.bad()) return Status::InvalidArgument("cannot read " + path);
  out.columns = static_cast<int>(out.points.size());
  return out;
}

// KITTI's Velodyne scans: float32 x y z reflectance a point, little-endian.
StatusOr<CloudFile> ReadKittiBin(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return Status::InvalidArgument("cannot read " + path);
  if (bytes.size() % 16 != 0) {
    return Status::InvalidArgument(path + " is not a KITTI scan: " + std::to_string(bytes.size()) +
                                   " bytes, not a whole number of 16-byte points");
  }
  CloudFile out;
  out.points.resize(bytes.size() / 16);
  for (size_t i = 0; i < out.points.size(); ++i) {
    float xyz[3];
    std::memcpy(xyz, bytes.data() + 16 * i, sizeof xyz);
    out.points[i] = Eigen::Vector3f(xyz[0], xyz[1], xyz[2]);
  }
  out.columns = static_cast<int>(out.points.size());
  return out;
}

}  // namespace

OrganisedCloud CloudFile::AsOrganised(bool wrap_columns) const {
  OrganisedCloud cloud;
  cloud.rows = rows;
  cloud.columns = columns;
  cloud.points = points;
  cloud.wrap_columns = wrap_columns;
  return cloud;
}

StatusOr<CloudFile> ReadCloudFile(const std::string& path) {
  if (!std::ifstream(path)) return Status::NotFound("cannot open point cloud " + path);
  const std::string ext = Extension(path);
  if (ext == "pcd") return ReadWithPcl(path, true);
  if (ext == "ply") return ReadWithPcl(path, false);
  if (ext == "xyz" || ext == "txt" || ext == "dat") return ReadText(path);
  if (ext == "bin") return ReadKittiBin(path);
  return Status::InvalidArgument(path + ": unknown point cloud format '" + ext +
                                 "' (expected .pcd, .ply, .bin, .xyz, .txt or .dat)");
}

StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const CloudFile& cloud, bool wrap_columns,
                                                    const PlaneExtractionParams& params,
                                                    PlaneExtractionStats* stats) {
  if (cloud.organised()) return ExtractPlanes(cloud.AsOrganised(wrap_columns), params, stats);
  return ExtractPlanes(cloud.points, params, stats);
}

}  // namespace mapd::robot
