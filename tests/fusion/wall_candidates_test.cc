// The neighbour search's candidate cache (fusion/wall_candidates.h) against
// searches of the index, under random moves, filings and removals of pieces.
// (Every fusion test also checks the consolidator's cached neighbour lists
// against fresh searches: neighbour_cache_check.cc.)
#include "fusion/wall_candidates.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <vector>

namespace mapd::fusion {
namespace {

using geometry::Segment2;
using geometry::Vec2;

// Pieces filed in an index as wall consolidation files them.
class FiledPieces {
 public:
  void File(ClusterId id, const Segment2& s) {
    Unfile(id);
    const int steps = FilingSteps(s);
    for (int i = 0; i <= steps; ++i) index_.Insert(FiledPoint(s, i, steps), id);
    segments_[id] = s;
  }
  void Unfile(ClusterId id) {
    auto it = segments_.find(id);
    if (it == segments_.end()) return;
    const int steps = FilingSteps(it->second);
    for (int i = 0; i <= steps; ++i) {
      index_.EraseIf(FiledPoint(it->second, i, steps), [id](ClusterId x) { return x == id; });
    }
    segments_.erase(it);
  }
  const Segment2* Find(ClusterId id) const {
    auto it = segments_.find(id);
    return it == segments_.end() ? nullptr : &it->second;
  }
  // The pieces a search of the bands finds, ascending.
  std::vector<ClusterId> Search(const std::vector<SearchBand>& bands) const {
    std::vector<ClusterId> out;
    for (const SearchBand& b : bands) {
      index_.ForEachNearSegment(b.segment, b.radius_m, [&](ClusterId id) { out.push_back(id); });
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }
  const PieceIndex& index() const { return index_; }

 private:
  PieceIndex index_{kPieceStepM};
  std::map<ClusterId, Segment2> segments_;
};

Segment2 RandomSegment(std::mt19937& rng, double extent_m) {
  std::uniform_real_distribution<double> coord(-extent_m, extent_m);
  std::uniform_real_distribution<double> length(0.0, 12.0), angle(-3.2, 3.2);
  const Vec2 a(coord(rng), coord(rng));
  const double t = angle(rng);
  return {a, a + length(rng) * Vec2(std::cos(t), std::sin(t))};
}

TEST(WallCandidatesTest, FiledInBandsTellsWhatASearchFinds) {
  std::mt19937 rng(3);
  FiledPieces pieces;
  for (ClusterId id = 0; id < 300; ++id) pieces.File(id, RandomSegment(rng, 40.0));
  std::uniform_real_distribution<double> radius(0.0, 3.0);
  for (int query = 0; query < 300; ++query) {
    const std::vector<SearchBand> bands = {{RandomSegment(rng, 40.0), radius(rng)},
                                           {RandomSegment(rng, 40.0), radius(rng)}};
    std::vector<PieceIndex::SegmentBand> cells;
    for (const SearchBand& b : bands) cells.push_back(pieces.index().BandOf(b.segment, b.radius_m));
    std::vector<ClusterId> told;
    for (ClusterId id = 0; id < 300; ++id) {
      if (FiledInBands(pieces.index(), *pieces.Find(id), cells)) told.push_back(id);
    }
    EXPECT_EQ(told, pieces.Search(bands)) << "query " << query;
  }
}

TEST(WallCandidatesTest, CandidatesHoldEverySearchResultAsPiecesMoveAndGo) {
  std::mt19937 rng(11);
  FiledPieces pieces;
  WallCandidates cache(&pieces.index(), [&](ClusterId id) { return pieces.Find(id); });
  constexpr ClusterId kPieces = 120;
  for (ClusterId id = 0; id < kPieces; ++id) {
    pieces.File(id, RandomSegment(rng, 25.0));
    cache.Filed(id);
  }
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::uniform_int_distribution<ClusterId> pick(0, kPieces - 1);
  size_t checked = 0;
  for (int step = 0; step < 20000; ++step) {
    const ClusterId id = pick(rng);
    const int what = static_cast<int>(rng() % 10);
    if (what == 0) {  // gone (erased or retired)
      pieces.Unfile(id);
      cache.Forget(id);
      continue;
    }
    const Segment2* now = pieces.Find(id);
    Segment2 s = now != nullptr && what > 1 ? *now : RandomSegment(rng, 25.0);
    if (what > 1) {  // a refit: moved a little (a whole jump when new or back)
      s.a += Vec2(jitter(rng), jitter(rng));
      s.b += Vec2(jitter(rng), jitter(rng));
    }
    pieces.File(id, s);
    cache.Filed(id);
    const std::vector<SearchBand> bands = {{s, 1.4}, {Segment2{s.b, s.b + (s.b - s.a)}, 0.8}};
    const std::vector<ClusterId>& candidates = cache.Candidates(id, bands);
    ASSERT_TRUE(std::is_sorted(candidates.begin(), candidates.end()));
    for (ClusterId found : pieces.Search(bands)) {
      ASSERT_TRUE(std::binary_search(candidates.begin(), candidates.end(), found))
          << "step " << step << ": piece " << found << " missing from " << id << "'s candidates";
      ++checked;
    }
  }
  EXPECT_GT(checked, 20000u);
}

}  // namespace
}  // namespace mapd::fusion
