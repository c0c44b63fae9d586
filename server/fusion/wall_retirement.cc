#include "fusion/wall_retirement.h"

#include <algorithm>
#include <cmath>

namespace mapd::fusion {

using geometry::Segment2;
using geometry::Vec2;

namespace {

constexpr double kTrimM = 0.5;
// A refit that moves both ends less than this keeps the piece's cells.
constexpr double kKeepCellsM = 0.25 * FreeSpaceGrid::kCellM;

bool Close(const Segment2& s, const Segment2& t) {
  const double d2 = kKeepCellsM * kKeepCellsM;
  return (s.a - t.a).squaredNorm() <= d2 && (s.b - t.b).squaredNorm() <= d2;
}

}  // namespace

std::vector<uint64_t> RetirementLedger::CellsOf(const Segment2& fitted) {
  const double length = fitted.length();
  std::vector<uint64_t> cells;
  if (!(length > 0.0)) {
    cells.push_back(FreeSpaceGrid::CellKeyOf(fitted.a));
    return cells;
  }
  const Vec2 u = fitted.direction() / length;
  const double trim = std::min(kTrimM, 0.25 * length);
  const double t0 = trim, t1 = length - trim;
  // Every cell the trimmed segment crosses: samples a quarter cell apart.
  const int steps =
      std::max(1, static_cast<int>(std::ceil((t1 - t0) / (0.25 * FreeSpaceGrid::kCellM))));
  cells.reserve(static_cast<size_t>(steps) + 1);
  for (int i = 0; i <= steps; ++i) {
    cells.push_back(FreeSpaceGrid::CellKeyOf(fitted.a + (t0 + (t1 - t0) * i / steps) * u));
  }
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  return cells;
}

void RetirementLedger::Attach(ClusterId piece, Entry* entry) {
  for (uint32_t i = 0; i < entry->cells.size(); ++i) {
    std::vector<std::pair<ClusterId, uint32_t>>& list = watchers_[entry->cells[i]];
    if (list.empty()) grid_->Watch(entry->cells[i], true);
    list.emplace_back(piece, i);
  }
}

void RetirementLedger::Detach(ClusterId piece, const Entry& entry) {
  for (uint64_t cell : entry.cells) {
    auto it = watchers_.find(cell);
    if (it == watchers_.end()) continue;
    auto& list = it->second;
    list.erase(std::remove_if(list.begin(), list.end(),
                              [piece](const auto& w) { return w.first == piece; }),
               list.end());
    if (list.empty()) {
      grid_->Watch(cell, false);
      watchers_.erase(it);
    }
  }
}

void RetirementLedger::Watch(ClusterId piece, const Segment2& fitted, bool supported) {
  auto it = entries_.find(piece);
  if (it != entries_.end() && Close(it->second.segment, fitted)) {
    if (supported && it->second.passes.find_first_not_of('\0') != std::string::npos) {
      std::fill(it->second.passes.begin(), it->second.passes.end(), '\0');
      it->second.seen_cells = 0;
    }
    return;
  }
  if (it != entries_.end()) {
    Detach(piece, it->second);
  } else {
    it = entries_.emplace(piece, Entry()).first;
  }
  Entry& entry = it->second;
  entry.segment = fitted;
  entry.cells = CellsOf(fitted);
  entry.passes.assign(entry.cells.size(), '\0');
  entry.seen_cells = 0;
  Attach(piece, &entry);
}

void RetirementLedger::Unwatch(ClusterId piece) {
  auto it = entries_.find(piece);
  if (it == entries_.end()) return;
  Detach(piece, it->second);
  entries_.erase(it);
}

void RetirementLedger::AddPasses(std::vector<uint64_t> cells, std::vector<ClusterId>* changed) {
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  const size_t first = changed->size();
  for (uint64_t cell : cells) {
    auto it = watchers_.find(cell);
    if (it == watchers_.end()) continue;
    for (const auto& [piece, index] : it->second) {
      Entry& entry = entries_.at(piece);
      auto& count = reinterpret_cast<unsigned char&>(entry.passes[index]);
      if (count == 255) continue;
      if (++count != views_) continue;
      ++entry.seen_cells;
      changed->push_back(piece);
    }
  }
  std::sort(changed->begin() + static_cast<std::ptrdiff_t>(first), changed->end());
  changed->erase(std::unique(changed->begin() + static_cast<std::ptrdiff_t>(first), changed->end()),
                 changed->end());
}

std::pair<size_t, size_t> RetirementLedger::SeenThrough(ClusterId piece) const {
  auto it = entries_.find(piece);
  if (it == entries_.end()) return {0, 0};
  return {it->second.cells.size(), it->second.seen_cells};
}

bool RetirementLedger::Restore(ClusterId piece, const Segment2& segment,
                               const std::string& passes) {
  Unwatch(piece);
  Entry entry;
  entry.segment = segment;
  entry.cells = CellsOf(segment);
  if (passes.size() != entry.cells.size()) return false;
  entry.passes = passes;
  for (char c : passes) entry.seen_cells += static_cast<unsigned char>(c) >= views_ ? 1 : 0;
  Attach(piece, &entries_.emplace(piece, std::move(entry)).first->second);
  return true;
}

}  // namespace mapd::fusion
