// An SVG picture of fused maps over the scenario's ground truth, one panel per
// map side by side, cropped to a window of the world (for docs/).
#ifndef MAPD_EVAL_SVG_H_
#define MAPD_EVAL_SVG_H_

#include <string>
#include <vector>

#include "common/status.h"
#include "sim/city_scenario.h"

namespace mapd::fusion::scenario {

struct SvgPanel {
  std::string title;
  std::vector<geometry::Segment2> segments;  // drawn over the ground truth
  std::vector<geometry::Segment2> raw;       // optional, drawn faint underneath
};

// Writes `path`; window [lo, hi] in metres, `px_per_m` scale.
Status WriteSvg(const std::string& path, const World& world, const std::vector<SvgPanel>& panels,
                const geometry::Vec2& lo, const geometry::Vec2& hi, double px_per_m);

}  // namespace mapd::fusion::scenario

#endif  // MAPD_EVAL_SVG_H_
