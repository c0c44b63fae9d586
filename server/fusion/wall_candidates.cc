#include "fusion/wall_candidates.h"

#include <algorithm>
#include <cmath>

namespace mapd::fusion {

using geometry::Segment2;

namespace {

// A cached search reads at most this many filings before searching again:
// while walls grow, many pieces are refiled at each update, and reading
// their filed points one by one would cost more than probing the cells.
constexpr uint64_t kMaxScan = 64;
// The log keeps at most this many filings (the older half goes).
constexpr size_t kMaxLog = 4096;
// Band ends may move this much less than kMarginM: what rounding of the
// bands' box and cell tests could take back.
constexpr double kMoveSlackM = 1e-6;

}  // namespace

int FilingSteps(const Segment2& s) {
  return std::max(1, static_cast<int>(std::ceil(s.length() / kPieceStepM)));
}

bool FiledInBands(const PieceIndex& index, const Segment2& filed,
                  const std::vector<PieceIndex::SegmentBand>& bands) {
  const int steps = FilingSteps(filed);
  for (int i = 0; i <= steps; ++i) {
    const CellKey key = index.KeyOf(FiledPoint(filed, i, steps));
    for (const PieceIndex::SegmentBand& band : bands) {
      if (band.Meets(key)) return true;
    }
  }
  return false;
}

void WallCandidates::Filed(ClusterId id) {
  filings_.push_back(id);
  if (filings_.size() > kMaxLog) {
    const size_t dropped = filings_.size() / 2;
    filings_.erase(filings_.begin(), filings_.begin() + static_cast<std::ptrdiff_t>(dropped));
    first_seq_ += dropped;
  }
}

void WallCandidates::Clear() { cache_.clear(); }

bool WallCandidates::Covers(const Entry& entry, const std::vector<SearchBand>& bands) {
  if (entry.searched.size() != bands.size()) return false;
  const double move2 = (kMarginM - kMoveSlackM) * (kMarginM - kMoveSlackM);
  for (size_t k = 0; k < bands.size(); ++k) {
    const SearchBand& now = bands[k];
    const SearchBand& then = entry.searched[k];
    if (now.radius_m != then.radius_m) return false;
    // Every point of the band's segment is then within kMarginM of the
    // searched one (segments are convex): its cells are within the widening.
    if ((now.segment.a - then.segment.a).squaredNorm() > move2 ||
        (now.segment.b - then.segment.b).squaredNorm() > move2) {
      return false;
    }
  }
  return true;
}

void WallCandidates::Search(const std::vector<SearchBand>& bands, Entry* entry) const {
  entry->searched = bands;
  entry->widened.clear();
  entry->ids.clear();
  for (const SearchBand& band : bands) {
    entry->widened.push_back(index_->BandOf(band.segment, band.radius_m + kMarginM));
    index_->ForEachInBand(entry->widened.back(),
                          [entry](ClusterId other) { entry->ids.push_back(other); });
  }
  std::sort(entry->ids.begin(), entry->ids.end());
  entry->ids.erase(std::unique(entry->ids.begin(), entry->ids.end()), entry->ids.end());
}

const std::vector<ClusterId>& WallCandidates::Candidates(ClusterId id,
                                                         const std::vector<SearchBand>& bands) {
  Entry& entry = cache_[id];
  const uint64_t end = first_seq_ + filings_.size();
  if (entry.seen < first_seq_ || end - entry.seen > kMaxScan || !Covers(entry, bands)) {
    Search(bands, &entry);
  } else if (entry.seen < end) {
    const size_t before = entry.ids.size();
    for (uint64_t k = entry.seen - first_seq_; k < filings_.size(); ++k) {
      const ClusterId other = filings_[k];
      const Segment2* filed = filed_segment_(other);
      if (filed != nullptr && FiledInBands(*index_, *filed, entry.widened)) {
        entry.ids.push_back(other);
      }
    }
    if (entry.ids.size() > before) {
      std::sort(entry.ids.begin(), entry.ids.end());
      entry.ids.erase(std::unique(entry.ids.begin(), entry.ids.end()), entry.ids.end());
    }
  }
  entry.seen = end;
  return entry.ids;
}

}  // namespace mapd::fusion
