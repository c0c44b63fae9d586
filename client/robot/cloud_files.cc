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
#include <fstream>
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

// PCD or PLY through PCL: a PCLPointCloud2 that must have x, y and z.
StatusOr<CloudFile> ReadWithPcl(const std::string& path, bool pcd) {
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
  return Status::InvalidArgument(path + ": unknown point cloud format '" + ext +
                                 "' (expected .pcd, .ply, .xyz, .txt or .dat)");
}

StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const CloudFile& cloud, bool wrap_columns,
                                                    const PlaneExtractionParams& params,
                                                    PlaneExtractionStats* stats) {
  if (cloud.organised()) return ExtractPlanes(cloud.AsOrganised(wrap_columns), params, stats);
  return ExtractPlanes(cloud.points, params, stats);
}

}  // namespace mapd::robot
