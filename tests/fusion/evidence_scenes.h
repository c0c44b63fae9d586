// Shared fixture of the free-space evidence tests (free_space_test.cc,
// occlusion_proof_test.cc): observations with a sensor origin, fed to an
// engine, and what it published on the wall line y = 0.
#ifndef MAPD_TESTS_FUSION_EVIDENCE_SCENES_H_
#define MAPD_TESTS_FUSION_EVIDENCE_SCENES_H_

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "fusion/engine.h"

namespace mapd::fusion {

struct Obs {
  ObservationId id;
  geometry::Vec2 origin;
  std::vector<GroundFeature> features;
};

// Appends observations with fresh ids (observation k + 1, features numbered on).
class SceneBuilder {
 public:
  void Add(const geometry::Vec2& origin, const std::vector<geometry::Segment2>& segments) {
    Obs o{next_obs_++, origin, {}};
    for (const geometry::Segment2& s : segments) {
      GroundFeature f;
      f.id = next_id_++;
      f.segment = s;
      o.features.push_back(f);
    }
    out_.push_back(std::move(o));
  }
  std::vector<Obs> Take() { return std::move(out_); }

 private:
  std::vector<Obs> out_;
  FeatureId next_id_ = 1;
  ObservationId next_obs_ = 1;
};

inline void Feed(FusionEngine* engine, const std::vector<Obs>& observations) {
  for (const Obs& o : observations) {
    ASSERT_TRUE(engine->AddFrom(o.id, 1, o.origin, o.features).ok());
  }
}

// The published features on the line y = 0, as x extents, ascending.
inline std::vector<std::pair<double, double>> OnWallLine(const FusionEngine& engine) {
  std::vector<std::pair<double, double>> out;
  for (const FusedFeature& f : engine.Published()) {
    if (std::abs(f.fitted.a.y()) > 0.05 || std::abs(f.fitted.b.y()) > 0.05) continue;
    out.push_back(
        {std::min(f.fitted.a.x(), f.fitted.b.x()), std::max(f.fitted.a.x(), f.fitted.b.x())});
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Ids, counts and endpoints to the micrometre (moment sums are rounded
// differently in another order; the partition is what must not change).
inline std::string Describe(const std::vector<FusedFeature>& fused) {
  std::string out;
  char line[256];
  for (const FusedFeature& f : fused) {
    std::snprintf(line, sizeof(line), "%llu %.6f %.6f %.6f %.6f %u %u\n",
                  static_cast<unsigned long long>(f.id), f.segment.a.x(), f.segment.a.y(),
                  f.segment.b.x(), f.segment.b.y(), f.support, f.member_count);
    out += line;
  }
  return out;
}

}  // namespace mapd::fusion

#endif  // MAPD_TESTS_FUSION_EVIDENCE_SCENES_H_
