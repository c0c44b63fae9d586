// The fuser's stall per snapshot, on a real fusion state: loads the newest
// snapshot of a mapd database (soak_bench --keep DIR leaves DIR/soak.db), then
// times FusionEngine::SaveState into a fresh string and into one reused, as
// MapCore does (docs/long-running.md, "Snapshots"), and LoadState (a restart).
// The database must have been written with the default fusion settings.
//
// Usage: snapshot_bench DB [RUNS]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "fusion/engine.h"
#include "storage/sqlite/store.h"

namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s DB [RUNS]\n", argv[0]);
    return 2;
  }
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 9;
  auto store = mapd::storage::SqliteStore::Open(argv[1], {});
  if (!store.ok()) {
    std::fprintf(stderr, "%s\n", store.status().ToString().c_str());
    return 1;
  }
  auto snapshot = (*store)->LatestSnapshot();
  if (!snapshot.ok()) {
    std::fprintf(stderr, "%s\n", snapshot.status().ToString().c_str());
    return 1;
  }
  mapd::fusion::FusionParams params;
  params.mode = mapd::fusion::FusionMode::kBounded;
  auto engine = mapd::fusion::FusionEngine::LoadState(params, snapshot->state);
  if (!engine.ok()) {
    std::fprintf(stderr, "%s\n", engine.status().ToString().c_str());
    return 1;
  }
  std::vector<double> fresh_ms, reused_ms, load_ms;
  std::string reused;
  for (int i = 0; i < runs; ++i) {
    auto t0 = Clock::now();
    std::string fresh;
    if (!(*engine)->SaveState(&fresh).ok()) return 1;
    fresh_ms.push_back(MsSince(t0));
    t0 = Clock::now();
    if (!(*engine)->SaveState(&reused).ok()) return 1;
    reused_ms.push_back(MsSince(t0));
    if (fresh != reused) {
      std::fprintf(stderr, "two saves of one engine differ\n");
      return 1;
    }
    t0 = Clock::now();
    if (!mapd::fusion::FusionEngine::LoadState(params, reused).ok()) return 1;
    load_ms.push_back(MsSince(t0));
  }
  std::printf(
      "state %.1f MB (%zu bytes), %d runs, medians: save into a fresh string %.1f ms, "
      "into a reused one %.1f ms, load %.1f ms\n",
      static_cast<double>(reused.size()) / 1e6, reused.size(), runs, Median(fresh_ms),
      Median(reused_ms), Median(load_ms));
  return 0;
}
