// Mean-shift clustering (Comaniciu & Meer 2002) as the two competing methods of
// the paper use it (feature-fusion paper, Li et al. 2023, section 2): on line
// orientations, an axial quantity with period pi, and on 2D feature centres.
#ifndef MAPD_EVAL_BASELINES_MEAN_SHIFT_H_
#define MAPD_EVAL_BASELINES_MEAN_SHIFT_H_

#include <cstdint>
#include <vector>

#include "geometry/segment2.h"

namespace mapd::fusion::baselines {

enum class Kernel {
  kFlat,      // weight 1 within the bandwidth, 0 beyond
  kGaussian,  // exp(-d^2 / (2 h^2)), truncated at 3 h
};

struct OrientationShiftParams {
  double bandwidth_rad = 2.0 * 3.14159265358979323846 / 180.0;  // h
  Kernel kernel = Kernel::kGaussian;
  // Orientations are binned at this resolution; every occupied bin seeds one
  // mean-shift run over the weighted bins ("binned" mean shift). Much smaller
  // than the bandwidth, so the binning changes the modes negligibly.
  double bin_rad = 0.05 * 3.14159265358979323846 / 180.0;
};

struct Modes {
  std::vector<double> mode;     // one value per mode (radians, or unused for 2D)
  std::vector<uint32_t> label;  // per input: index into mode
};

// Mean shift on orientations theta in [0, pi) (wrapped, period pi), weighted.
// Converged seeds closer than h / 2 are one mode. Deterministic.
// REQUIRES: theta_rad.size() == weights.size(), weights > 0.
Modes OrientationModes(const std::vector<double>& theta_rad, const std::vector<double>& weights,
                       const OrientationShiftParams& params);

struct CentreShiftParams {
  // h. Below the 2 m spacing of parallel walls that must stay apart (a flat
  // kernel of h = 2 m already merges them); the paper's point is that no single
  // value suits both long walls and close ones.
  double bandwidth_m = 1.5;
  Kernel kernel = Kernel::kFlat;
};

// Mean shift on 2D points, seeded from the means of the occupied cells of an
// h-wide grid (sklearn's bin seeding); modes within h of a denser mode are
// dropped; every point joins its nearest mode. Returns per-point labels and the
// mode positions. Deterministic.
std::vector<uint32_t> CentreModes(const std::vector<geometry::Vec2>& points,
                                  const CentreShiftParams& params,
                                  std::vector<geometry::Vec2>* modes);

// The orientation of a segment in [0, pi).
double AxialAngle(const geometry::Segment2& s);

// Accumulates the weighted mean of axial orientations (the doubled-angle mean).
class AxialMean {
 public:
  void Add(const geometry::Segment2& s, double weight);
  // Unit direction of the mean orientation. REQUIRES: something was added.
  geometry::Vec2 Direction() const;

 private:
  double c_ = 0.0;  // sum of w cos(2 theta)
  double s_ = 0.0;  // sum of w sin(2 theta)
};

}  // namespace mapd::fusion::baselines

#endif  // MAPD_EVAL_BASELINES_MEAN_SHIFT_H_
