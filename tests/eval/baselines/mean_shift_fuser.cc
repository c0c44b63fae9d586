#include "eval/baselines/mean_shift_fuser.h"

#include <utility>

namespace mapd::fusion::baselines {

using geometry::Vec2;

std::vector<std::vector<uint32_t>> MeanShiftFuser::Cluster(
    const std::vector<Member>& members) const {
  std::vector<std::vector<uint32_t>> clusters;
  for (const std::vector<uint32_t>& group : OrientationGroups(members, params_.orientation)) {
    std::vector<Vec2> centres;
    centres.reserve(group.size());
    for (uint32_t i : group) centres.push_back(members[i].feature.segment.midpoint());
    std::vector<Vec2> modes;
    const std::vector<uint32_t> label = CentreModes(centres, params_.centre, &modes);
    std::vector<std::vector<uint32_t>> local(modes.size());
    for (size_t k = 0; k < group.size(); ++k) local[label[k]].push_back(group[k]);
    for (std::vector<uint32_t>& c : local) {
      if (!c.empty()) clusters.push_back(std::move(c));
    }
  }
  return clusters;
}

geometry::Line2 MeanShiftFuser::MergeLine(const std::vector<Member>& members,
                                          const std::vector<uint32_t>& cluster) const {
  AxialMean orientation;
  Vec2 middle = Vec2::Zero();
  for (uint32_t i : cluster) {
    orientation.Add(members[i].feature.segment, 1.0);
    middle += members[i].feature.segment.midpoint();
  }
  geometry::Line2 line;
  line.point = middle / static_cast<double>(cluster.size());
  line.direction = geometry::CanonicalDirection(orientation.Direction());
  return line;
}

}  // namespace mapd::fusion::baselines
