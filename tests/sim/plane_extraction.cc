#include "sim/plane_extraction.h"

#include <algorithm>
#include <map>

namespace mapd::sim {

StatusOr<std::vector<ExtractedPlane>> ExtractPlanes(const LidarScan& scan,
                                                    const PlaneExtractionParams& params,
                                                    ExtractionStats* stats) {
  const size_t n =
      static_cast<size_t>(std::max(scan.beams, 0)) * static_cast<size_t>(std::max(scan.columns, 0));
  if (scan.beams < 1 || scan.columns < 1 || scan.points.size() != n || scan.labels.size() != n) {
    return Status::InvalidArgument("plane extraction: scan is not beams x columns points");
  }
  robot::OrganisedCloud cloud;
  cloud.rows = scan.beams;
  cloud.columns = scan.columns;
  cloud.points = scan.points;
  cloud.wrap_columns = true;  // a 360 deg spinning LiDAR
  auto planes = robot::ExtractPlanes(cloud, params, stats);
  if (!planes.ok()) return planes.status();
  std::vector<ExtractedPlane> out;
  for (const robot::ExtractedPlane& p : *planes) {
    ExtractedPlane plane;
    plane.feature = p.feature;
    plane.inliers = p.indices.size();
    plane.rms_m = p.rms_m;
    std::map<int, size_t> votes;
    for (int i : p.indices) ++votes[scan.labels[static_cast<size_t>(i)]];
    plane.label = std::max_element(votes.begin(), votes.end(), [](const auto& a, const auto& b) {
                    return a.second < b.second;
                  })->first;
    out.push_back(std::move(plane));
  }
  return out;
}

}  // namespace mapd::sim
