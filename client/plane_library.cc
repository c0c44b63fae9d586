#include "client/plane_library.h"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <utility>

#include "client/robot/c_api.h"

namespace mapd::client {

// The C interface's functions, looked up once.
struct PlaneLibrary::Api {
  decltype(&mapd_read_cloud) read_cloud;
  decltype(&mapd_cloud_size) cloud_size;
  decltype(&mapd_cloud_shape) cloud_shape;
  decltype(&mapd_cloud_points) cloud_points;
  decltype(&mapd_cloud_free) cloud_free;
  decltype(&mapd_extract_planes) extract_planes;
  decltype(&mapd_planes_count) planes_count;
  decltype(&mapd_planes_get) planes_get;
  decltype(&mapd_planes_boundary) planes_boundary;
  decltype(&mapd_planes_free) planes_free;
};

namespace {

constexpr char kLibrary[] = "libmapd_robot_c.so";

// The directory of the running mapctl ("" if unknown).
std::string ExecutableDir() {
  char buffer[4096];
  const ssize_t n = readlink("/proc/self/exe", buffer, sizeof(buffer) - 1);
  if (n <= 0) return "";
  const std::string exe(buffer, static_cast<size_t>(n));
  return exe.substr(0, exe.find_last_of('/'));
}

// One of the library's symbols, or nullptr (and the name in *missing).
template <typename F>
bool FindSymbol(void* handle, const char* name, F* out, std::string* missing) {
  *out = reinterpret_cast<F>(dlsym(handle, name));
  if (*out == nullptr) *missing = name;
  return *out != nullptr;
}

}  // namespace

PlaneLibrary::PlaneLibrary(void* handle, std::string path, std::unique_ptr<Api> api)
    : handle_(handle), path_(std::move(path)), api_(std::move(api)) {}

PlaneLibrary::~PlaneLibrary() { dlclose(handle_); }

StatusOr<std::unique_ptr<PlaneLibrary>> PlaneLibrary::Load() {
  std::vector<std::string> candidates;
  if (const char* env = std::getenv("MAPD_ROBOT_LIBRARY"); env != nullptr && env[0] != '\0') {
    candidates.push_back(env);
  }
  const std::string dir = ExecutableDir();
  if (!dir.empty()) {
    candidates.push_back(dir + "/../lib/" + kLibrary);
    candidates.push_back(dir + "/robot/" + kLibrary);
  }
  candidates.push_back(kLibrary);  // the system's search path
  std::string tried;
  for (const std::string& path : candidates) {
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      if (!tried.empty()) tried += ", ";
      tried += path;
      continue;
    }
    auto api = std::make_unique<Api>();
    std::string missing;
    if (!FindSymbol(handle, "mapd_read_cloud", &api->read_cloud, &missing) ||
        !FindSymbol(handle, "mapd_cloud_size", &api->cloud_size, &missing) ||
        !FindSymbol(handle, "mapd_cloud_shape", &api->cloud_shape, &missing) ||
        !FindSymbol(handle, "mapd_cloud_points", &api->cloud_points, &missing) ||
        !FindSymbol(handle, "mapd_cloud_free", &api->cloud_free, &missing) ||
        !FindSymbol(handle, "mapd_extract_planes", &api->extract_planes, &missing) ||
        !FindSymbol(handle, "mapd_planes_count", &api->planes_count, &missing) ||
        !FindSymbol(handle, "mapd_planes_get", &api->planes_get, &missing) ||
        !FindSymbol(handle, "mapd_planes_boundary", &api->planes_boundary, &missing) ||
        !FindSymbol(handle, "mapd_planes_free", &api->planes_free, &missing)) {
      dlclose(handle);
      std::string message = path;
      message += " is not the robot library's C interface (no ";
      message += missing;
      message += ")";
      return Status::FailedPrecondition(message);
    }
    return std::unique_ptr<PlaneLibrary>(new PlaneLibrary(handle, path, std::move(api)));
  }
  return Status::NotFound(
      std::string(kLibrary) +
      " (the robot library's plane extractor, built with MAPD_WITH_ROBOT_PLANES=ON and PCL) "
      "was not found: tried " +
      tried + "; set MAPD_ROBOT_LIBRARY to its path");
}

StatusOr<std::vector<geometry::PlaneFeature>> PlaneLibrary::PlanesOfFile(const std::string& path,
                                                                         bool wrap_columns) const {
  char error[1024] = "";
  mapd_cloud* cloud = nullptr;
  if (int rc = api_->read_cloud(path.c_str(), &cloud, error, sizeof error); rc != 0) {
    return Status(static_cast<StatusCode>(rc), error);
  }
  int rows = 0, columns = 0;
  api_->cloud_shape(cloud, &rows, &columns);
  mapd_planes* planes = nullptr;
  const int rc =
      api_->extract_planes(api_->cloud_points(cloud), api_->cloud_size(cloud), rows, columns,
                           wrap_columns ? 1 : 0, nullptr, &planes, error, sizeof error);
  api_->cloud_free(cloud);
  if (rc != 0) return Status(static_cast<StatusCode>(rc), path + ": " + error);
  std::vector<geometry::PlaneFeature> out(api_->planes_count(planes));
  for (size_t i = 0; i < out.size(); ++i) {
    double normal[3], offset = 0, rms = 0;
    size_t boundary_size = 0, inliers = 0;
    api_->planes_get(planes, i, normal, &offset, &rms, &boundary_size, &inliers);
    std::vector<double> xyz(3 * boundary_size);
    api_->planes_boundary(planes, i, xyz.data());
    out[i].normal = Eigen::Vector3d(normal[0], normal[1], normal[2]);
    out[i].offset = offset;
    for (size_t k = 0; k < boundary_size; ++k) {
      out[i].boundary.emplace_back(xyz[3 * k], xyz[3 * k + 1], xyz[3 * k + 2]);
    }
  }
  api_->planes_free(planes);
  return out;
}

}  // namespace mapd::client
