// Corner matching (docs/algorithms.md B.4): generated corner sets with known
// transforms, and TEASER++'s correspondence benchmarks with outliers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "common/temp_dir.h"
#include "eval/backtracking_mcs.h"
#include "voxel/corner_matching.h"
#include "voxel/support/corner_scene.h"
#include "voxel/support/ply_reader.h"

namespace mapd::voxel {
namespace {

using testing::CornerScene;
using testing::CornerSceneOptions;
using testing::MakeCornerScene;
using testing::RotationErrorDeg;
using testing::TranslationError;

int CountTrue(const std::vector<CornerPair>& found, const std::vector<CornerPair>& truth) {
  int n = 0;
  for (const CornerPair& p : found) {
    if (std::binary_search(truth.begin(), truth.end(), p)) ++n;
  }
  return n;
}

// A generated scene of num_a corners in A with the default options.
CornerScene SceneOf(int num_a, uint32_t seed) {
  CornerSceneOptions o;
  o.num_a = num_a;
  o.seed = seed;
  return MakeCornerScene(o);
}

TEST(CornerMatchingParamsTest, ValidatesEveryField) {
  EXPECT_TRUE(CornerMatchingParams{}.Validate().ok());
  CornerMatchingParams p;
  p.consistency_distance_m = 0.0;
  EXPECT_EQ(p.Validate().code(), StatusCode::kInvalidArgument);
  p = {};
  p.top_k = 0;
  EXPECT_FALSE(p.Validate().ok());
  p = {};
  p.min_matches = 2;
  EXPECT_FALSE(p.Validate().ok());
  p = {};
  p.max_search_seconds = -1;
  EXPECT_FALSE(p.Validate().ok());
  CornerSet bad(3);
  bad[1].normals[2] = Eigen::Vector3d::Zero();
  EXPECT_EQ(MatchCorners(bad, bad, CornerMatchingParams{}).status().code(),
            StatusCode::kInvalidArgument);
}

TEST(CornerSignatureTest, IsInvariantToRotationOrderAndSign) {
  Corner c;
  c.normals = {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.6, 0.8, 0),
               Eigen::Vector3d(0, 0.28, 0.96)};
  const CornerSignature s = ComputeSignature(c);
  EXPECT_LE(s.plane_angles_rad[0], s.plane_angles_rad[1]);
  EXPECT_LE(s.plane_angles_rad[1], s.plane_angles_rad[2]);
  Corner d = c;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  d.normals = {-(R * c.normals[2]), R * c.normals[0], -(R * c.normals[1])};
  const CornerSignature t = ComputeSignature(d);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(s.plane_angles_rad[k], t.plane_angles_rad[k], 1e-12);
  Corner box;  // default: orthogonal
  for (double a : ComputeSignature(box).plane_angles_rad) EXPECT_NEAR(a, M_PI / 2, 1e-12);
}

struct SceneCase {
  int num_a;
  uint32_t seed;
  double manhattan_fraction;
  bool use_normals = true;
};

void PrintTo(const SceneCase& c, std::ostream* out) {
  *out << "seed " << c.seed << ", " << c.num_a << " corners, manhattan " << c.manhattan_fraction
       << (c.use_normals ? "" : ", no normals");
}

std::string SceneCaseName(const ::testing::TestParamInfo<SceneCase>& param) {
  const SceneCase& c = param.param;
  return "seed" + std::to_string(c.seed) + "_corners" + std::to_string(c.num_a) + "_manhattan" +
         std::to_string(static_cast<int>(c.manhattan_fraction * 100)) +
         (c.use_normals ? "" : "_no_normals");
}

class GeneratedSceneTest : public ::testing::TestWithParam<SceneCase> {};

TEST_P(GeneratedSceneTest, BothMethodsRecoverTheTransform) {
  CornerSceneOptions o;
  o.num_a = GetParam().num_a;
  o.seed = GetParam().seed;
  o.manhattan_fraction = GetParam().manhattan_fraction;
  o.noise_m = 0.01 + 0.01 * (o.seed % 2);  // 1-2 cm
  const CornerScene scene = MakeCornerScene(o);

  CornerMatchingParams params;
  params.use_normals = GetParam().use_normals;
  const std::vector<CornerPair> candidates = SelectCandidatePairs(scene.a, scene.b, params);
  const int truth_kept = CountTrue(candidates, scene.truth);
  EXPECT_GE(truth_kept, 0.9 * scene.truth.size()) << "signatures dropped true pairs";

  int clique_size = 0;
  for (const NamedSearch& method : SearchesToCompare()) {
    SCOPED_TRACE(method.name);
    params.search = method.search;
    // The backtracking search finds the answer early but takes long to
    // exhaust its search space (see docs/voxel-matching.md): cap it.
    params.max_search_seconds = method.search ? 2.0 : 20.0;
    const StatusOr<CornerMatchResult> r = MatchCorners(scene.a, scene.b, params);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    ASSERT_TRUE(r->transform_valid);
    EXPECT_LT(RotationErrorDeg(r->T_a_b, scene.T_a_b), 1.0);
    EXPECT_LT(TranslationError(r->T_a_b, scene.T_a_b), 0.05);
    EXPECT_EQ(r->matched_count, static_cast<int>(r->correspondences.size()));
    const int correct = CountTrue(r->correspondences, scene.truth);
    EXPECT_GE(correct, 0.8 * scene.truth.size());
    EXPECT_GE(correct, r->matched_count - 1) << "at most one wrong pair";
    EXPECT_LT(r->rms_residual_m, 0.05);
    EXPECT_EQ(r->candidate_pairs, static_cast<int>(candidates.size()));
    if (!method.search) {  // the maximum clique
      EXPECT_TRUE(r->proven_optimal);
      clique_size = r->matched_count;
    } else {
      EXPECT_GE(clique_size, r->matched_count) << "the exact clique is at least as large";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, GeneratedSceneTest,
                         ::testing::Values(SceneCase{40, 1, 0.5}, SceneCase{60, 2, 0.5},
                                           SceneCase{80, 3, 0.5}, SceneCase{100, 4, 0.5},
                                           SceneCase{60, 5, 1.0}, SceneCase{100, 6, 1.0},
                                           SceneCase{70, 7, 0.0}, SceneCase{50, 8, 0.5},
                                           SceneCase{60, 9, 0.5, false},
                                           SceneCase{100, 10, 1.0, false}),
                         SceneCaseName);

TEST(CornerMatchingTest, ExhaustiveBacktrackingEqualsMaxCliqueSize) {
  const CornerScene scene = SceneOf(20, 11);
  CornerMatchingParams params;
  params.top_k = 3;
  const auto pairs = SelectCandidatePairs(scene.a, scene.b, params);
  std::vector<Eigen::Vector3d> pa, pb;
  for (const Corner& c : scene.a) pa.push_back(c.position);
  for (const Corner& c : scene.b) pb.push_back(c.position);
  const BitGraph g = BuildConsistencyGraph(pa, pb, pairs, params.consistency_distance_m);
  BacktrackingOptions bo;
  bo.shortcut_matches = 0;  // exact
  const BacktrackingResult bt = FindCommonSubgraphByBacktracking(g, pairs, pa, pb, bo);
  ASSERT_TRUE(bt.exhausted_search_space);
  const MaxCliqueResult mc = FindMaximumClique(g);
  ASSERT_FALSE(bt.schemes.empty());
  EXPECT_EQ(bt.schemes.front().size(), mc.clique.size());
  EXPECT_TRUE(IsClique(g, bt.schemes.front()));
}

TEST(CornerMatchingTest, ExcludedPairsAreNeverUsed) {
  const CornerScene scene = SceneOf(30, 5);
  CornerMatchingParams params;
  const StatusOr<CornerMatchResult> first = MatchCorners(scene.a, scene.b, params);
  ASSERT_TRUE(first.ok()) << first.status().ToString();
  ASSERT_GE(first->matched_count, 4);
  // Exclude half of the first solution's pairs: the next solution avoids them
  // and is smaller by at most that many.
  for (std::size_t i = 0; i < first->correspondences.size(); i += 2) {
    params.excluded_pairs.emplace_back(first->correspondences[i].a, first->correspondences[i].b);
  }
  const StatusOr<CornerMatchResult> second = MatchCorners(scene.a, scene.b, params);
  ASSERT_TRUE(second.ok()) << second.status().ToString();
  for (const CornerPair& p : second->correspondences) {
    EXPECT_EQ(std::count(params.excluded_pairs.begin(), params.excluded_pairs.end(),
                         std::make_pair(p.a, p.b)),
              0)
        << p.a << "," << p.b;
  }
  EXPECT_GE(second->matched_count,
            first->matched_count - static_cast<int>(params.excluded_pairs.size()));
  EXPECT_LT(second->matched_count, first->matched_count);
}

TEST(CornerMatchingTest, MatcherSearchesTheGraphARebuildWouldGive) {
  const CornerScene scene = SceneOf(30, 7);
  CornerMatchingParams params;
  params.use_normals = false;  // MatchCandidatePairs's graph has no normals test
  auto matcher = CornerMatcher::Create(scene.a, scene.b, params);
  ASSERT_TRUE(matcher.ok()) << matcher.status().ToString();
  std::vector<Eigen::Vector3d> points_a, points_b;
  for (const Corner& c : scene.a) points_a.push_back(c.position);
  for (const Corner& c : scene.b) points_b.push_back(c.position);
  const std::vector<CornerPair> all = SelectCandidatePairs(scene.a, scene.b, params);
  std::vector<std::pair<int, int>> excluded;
  for (int round = 0; round < 3; ++round) {
    std::vector<CornerPair> kept;
    for (const CornerPair& p : all) {
      if (std::count(excluded.begin(), excluded.end(), std::make_pair(p.a, p.b)) == 0) {
        kept.push_back(p);
      }
    }
    const auto rebuilt = MatchCandidatePairs(points_a, points_b, kept, params);
    const auto reused = matcher->Match(excluded, params.max_search_seconds);
    ASSERT_TRUE(rebuilt.ok() && reused.ok());
    EXPECT_EQ(reused->candidate_pairs, rebuilt->candidate_pairs);
    EXPECT_EQ(reused->graph_edges, rebuilt->graph_edges);
    EXPECT_EQ(reused->correspondences, rebuilt->correspondences);
    EXPECT_TRUE(reused->T_a_b.isApprox(rebuilt->T_a_b)) << "round " << round;
    ASSERT_GE(reused->matched_count, 3) << "round " << round;
    // The next round excludes this solution, as the merge does.
    for (const CornerPair& p : reused->correspondences) excluded.emplace_back(p.a, p.b);
  }
}

TEST(CornerMatchingTest, CandidateCapLowersTopKForEveryCorner) {
  const CornerScene scene = SceneOf(60, 8);
  CornerMatchingParams params;
  params.top_k = 32;
  const std::size_t uncapped = SelectCandidatePairs(scene.a, scene.b, params).size();
  params.max_candidate_pairs = 400;
  ASSERT_GT(uncapped, 400u);
  const auto capped = SelectCandidatePairs(scene.a, scene.b, params);
  EXPECT_LE(capped.size(), 400u);
  EXPECT_GT(capped.size(), 200u);  // the largest k that fits, not k = 1
  // The true pairs rank first (context score), so the capped graph still
  // holds the answer.
  const StatusOr<CornerMatchResult> r = MatchCorners(scene.a, scene.b, params);
  ASSERT_TRUE(r.ok() && r->transform_valid);
  EXPECT_LT(RotationErrorDeg(r->T_a_b, scene.T_a_b), 1.0);
  // A cap below one pair per corner keeps one pair per corner.
  params.max_candidate_pairs = 1;
  const auto one = SelectCandidatePairs(scene.a, scene.b, params);
  EXPECT_GE(one.size(), 1u);
  EXPECT_LE(one.size(), scene.a.size() + scene.b.size());
  params.max_candidate_pairs = -1;
  EXPECT_EQ(params.Validate().code(), StatusCode::kInvalidArgument);
}

// Corners whose normals are off by 15 deg (real maps: 5-30 deg, the plane
// triple seen differs) fail the strict signature test; the looser stage that
// MergeParams::looser_tolerances tries next keeps the true pairs.
TEST(CornerMatchingTest, LooseTolerancesKeepCornersWithNoisyNormals) {
  CornerSceneOptions o;
  o.num_a = 40;
  o.seed = 13;
  o.normal_noise_rad = 15.0 * M_PI / 180.0;
  const CornerScene scene = MakeCornerScene(o);
  CornerMatchingParams strict;
  strict.top_k = 32;
  CornerMatchingParams loose = strict;
  loose.signature_tolerance_rad = 40.0 * M_PI / 180.0;
  loose.normal_tolerance_rad = 30.0 * M_PI / 180.0;
  const int strict_true = CountTrue(SelectCandidatePairs(scene.a, scene.b, strict), scene.truth);
  const int loose_true = CountTrue(SelectCandidatePairs(scene.a, scene.b, loose), scene.truth);
  EXPECT_GT(loose_true, strict_true + static_cast<int>(scene.truth.size()) / 4)
      << strict_true << " vs " << loose_true << " of " << scene.truth.size();
  const StatusOr<CornerMatchResult> r = MatchCorners(scene.a, scene.b, loose);
  ASSERT_TRUE(r.ok() && r->transform_valid);
  EXPECT_GE(CountTrue(r->correspondences, scene.truth), static_cast<int>(scene.truth.size()) / 2);
  EXPECT_LT(RotationErrorDeg(r->T_a_b, scene.T_a_b), 1.0);
  EXPECT_LT(TranslationError(r->T_a_b, scene.T_a_b), 0.05);
}

TEST(CornerMatchingTest, UnrelatedMapsGiveOnlyChanceMatches) {
  CornerSceneOptions o;
  o.num_a = 60;
  o.seed = 21;
  const CornerScene a = MakeCornerScene(o);
  o.seed = 22;
  const CornerScene b = MakeCornerScene(o);
  const StatusOr<CornerMatchResult> r = MatchCorners(a.a, b.b, CornerMatchingParams{});
  ASSERT_TRUE(r.ok());
  EXPECT_LE(r->matched_count, 5);
}

// A scene symmetric under a half turn about z: matching it to itself has two
// equal-size answers, identity and the half turn; the score decides.
TEST(CornerMatchingTest, TiesGoToTheBestScore) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  const Eigen::Isometry3d half_turn(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  CornerSet a;
  for (int i = 0; i < 8; ++i) {
    Corner c;
    c.position = {u(rng), u(rng), u(rng)};
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(u(rng), Eigen::Vector3d(1, 2, u(rng)).normalized()).matrix();
    c.normals = {R.col(0), R.col(1), R.col(2)};
    Corner d = c;
    d.position = half_turn * c.position;
    for (auto& n : d.normals) n = half_turn.linear() * n;
    a.push_back(c);
    a.push_back(d);
  }
  for (const NamedSearch& method : SearchesToCompare()) {
    SCOPED_TRACE(method.name);
    CornerMatchingParams params;
    params.search = method.search;
    for (const Eigen::Isometry3d& wanted : {Eigen::Isometry3d::Identity(), half_turn}) {
      const auto score = [&](const Eigen::Isometry3d& T) {
        return -(T.matrix() - wanted.matrix()).norm();
      };
      const StatusOr<CornerMatchResult> r = MatchCorners(a, a, params, score);
      ASSERT_TRUE(r.ok());
      EXPECT_EQ(r->matched_count, 16);
      EXPECT_GE(r->tied_solutions, 2);
      EXPECT_LT((r->T_a_b.matrix() - wanted.matrix()).norm(), 1e-6);
    }
  }
}

// ---------------------------------------------------------------------------
// TEASER++ benchmark sets: src[i] <-> dst[i] putative correspondences,
// dst = s R src + t for the inliers.

std::vector<double> ReadNumbers(const std::string& path) {
  std::ifstream in(path);
  std::vector<double> v;
  std::string token;
  while (std::getline(in, token)) {
    std::stringstream line(token);
    std::string cell;
    while (std::getline(line, cell, ',')) {
      if (!cell.empty()) v.push_back(std::stod(cell));
    }
  }
  return v;
}

std::map<std::string, double> ReadParameters(const std::string& path) {
  std::ifstream in(path);
  std::map<std::string, double> m;
  std::string line;
  while (std::getline(in, line)) {
    const size_t colon = line.find(':');
    if (colon != std::string::npos) m[line.substr(0, colon)] = std::stod(line.substr(colon + 1));
  }
  return m;
}

class TeaserBenchmarkTest : public ::testing::TestWithParam<int> {};

TEST_P(TeaserBenchmarkTest, MaxCliqueRejectsOutliers) {
  const char* shared = std::getenv("MAPD_SHARED_DIR");
  const std::filesystem::path dir = std::filesystem::path(shared ? shared : "") / "data" /
                                    "matching" / ("benchmark_" + std::to_string(GetParam()));
  if (shared == nullptr || !std::filesystem::exists(dir / "src.ply")) {
    GTEST_SKIP() << "no " << dir << " (set MAPD_SHARED_DIR)";
  }
  const auto src_or = testing::ReadPlyVertices((dir / "src.ply").string());
  const auto dst_or = testing::ReadPlyVertices((dir / "dst.ply").string());
  ASSERT_TRUE(src_or.ok()) << src_or.status().ToString();
  ASSERT_TRUE(dst_or.ok()) << dst_or.status().ToString();
  const std::vector<Eigen::Vector3d>& src = src_or.value();
  const std::vector<Eigen::Vector3d>& dst = dst_or.value();
  ASSERT_EQ(src.size(), dst.size());
  const std::vector<double> r = ReadNumbers((dir / "R_ref.csv").string());
  const std::vector<double> t = ReadNumbers((dir / "t_ref.csv").string());
  const std::vector<double> s = ReadNumbers((dir / "s_ref.csv").string());
  ASSERT_EQ(r.size(), 9u);
  ASSERT_EQ(t.size(), 3u);
  ASSERT_EQ(s.size(), 1u);
  auto params_txt = ReadParameters((dir / "parameters.txt").string());
  const double noise_bound = params_txt.at("Noise Bound");
  const double outlier_ratio = params_txt.at("Outlier Ratio");
  Eigen::Isometry3d T_ref = Eigen::Isometry3d::Identity();
  T_ref.linear() = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(r.data());
  T_ref.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
  const double scale = s[0];

  // Every set has s != 1. Pairwise distances are only comparable at one
  // scale, so the known scale is applied to src (dst = R (s src) + t); the
  // scale is then re-estimated from the inliers as a check.
  std::vector<Eigen::Vector3d> scaled_src;
  for (const auto& p : src) scaled_src.push_back(scale * p);
  std::vector<CornerPair> pairs;
  for (int i = 0; i < static_cast<int>(src.size()); ++i) pairs.push_back({i, i});

  const int n = static_cast<int>(src.size());
  const int inliers = n - static_cast<int>(std::lround(outlier_ratio * n));
  double extent = 0.0;
  for (const auto& p : dst) extent = std::max(extent, (p - dst.front()).norm());

  for (const NamedSearch& method : SearchesToCompare()) {
    SCOPED_TRACE(method.name);
    CornerMatchingParams params;
    params.search = method.search;
    // Each point is off by at most the noise bound: distances by twice that.
    params.consistency_distance_m = 2.0 * noise_bound;
    const StatusOr<CornerMatchResult> m = MatchCandidatePairs(dst, scaled_src, pairs, params);
    ASSERT_TRUE(m.ok()) << m.status().ToString();
    ASSERT_TRUE(m->transform_valid);
    EXPECT_GE(m->matched_count, inliers);
    EXPECT_LT(RotationErrorDeg(m->T_a_b, T_ref), 2.0);
    EXPECT_LT(TranslationError(m->T_a_b, T_ref), 0.01 * extent + noise_bound);
    if (!method.search) {  // the maximum clique
      EXPECT_TRUE(m->proven_optimal);
    }

    Eigen::Matrix3Xd a(3, m->matched_count), b(3, m->matched_count);
    for (int k = 0; k < m->matched_count; ++k) {
      a.col(k) = dst[m->correspondences[k].a];
      b.col(k) = src[m->correspondences[k].b];
    }
    const Eigen::Matrix4d sim = Eigen::umeyama(b, a, /*with_scaling=*/true);
    const double s_est = std::cbrt(sim.topLeftCorner<3, 3>().determinant());
    EXPECT_NEAR(s_est / scale, 1.0, 0.01);
  }
}

INSTANTIATE_TEST_SUITE_P(Sets, TeaserBenchmarkTest, ::testing::Range(1, 7));

// ---------------------------------------------------------------------------

TEST(PlyReaderTest, ReadsAsciiAndBinaryLittleEndian) {
  testing::TempDir dir;
  {
    std::ofstream f(dir.File("a.ply"));
    f << "ply\nformat ascii 1.0\ncomment x\nelement vertex 2\nproperty float x\n"
         "property float y\nproperty float z\nproperty uchar red\nelement face 0\n"
         "property list uchar int vertex_indices\nend_header\n1 2 3 255\n-4.5 5 6e1 0\n";
  }
  auto a = testing::ReadPlyVertices(dir.File("a.ply"));
  ASSERT_TRUE(a.ok()) << a.status().ToString();
  ASSERT_EQ(a->size(), 2u);
  EXPECT_EQ((*a)[1], Eigen::Vector3d(-4.5, 5, 60));
  {
    std::ofstream f(dir.File("b.ply"), std::ios::binary);
    f << "ply\r\nformat binary_little_endian 1.0\r\nelement vertex 2\r\nproperty double x\r\n"
         "property uchar tag\r\nproperty double y\r\nproperty float32 z\r\nend_header\n";
    for (int i = 0; i < 2; ++i) {
      const double x = 0.1 + i, y = -2.25 * i;
      const unsigned char tag = 7;
      const float z = 3.5f;
      f.write(reinterpret_cast<const char*>(&x), 8);
      f.write(reinterpret_cast<const char*>(&tag), 1);
      f.write(reinterpret_cast<const char*>(&y), 8);
      f.write(reinterpret_cast<const char*>(&z), 4);
    }
  }
  auto b = testing::ReadPlyVertices(dir.File("b.ply"));
  ASSERT_TRUE(b.ok()) << b.status().ToString();
  ASSERT_EQ(b->size(), 2u);
  EXPECT_EQ((*b)[1], Eigen::Vector3d(1.1, -2.25, 3.5));
  EXPECT_FALSE(testing::ReadPlyVertices(dir.File("missing.ply")).ok());
}

}  // namespace
}  // namespace mapd::voxel
