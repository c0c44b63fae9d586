// The observation log's write path on each backend, WITHOUT mapd: batches of
// `features` lines in group transactions of `group` batches (as mapd's writer
// groups robots' batches), one writer. Reports batches/s and the commit
// latency of a group (p50/p99), i.e. the storage share of an acknowledgement.
//
// This measures the library only: mapd cannot run on PostgreSQL yet (issue
// 41, step 2), so the end-to-end figure through a real mapd comes with it.
// PostgreSQL runs in a throw-away cluster with fsync ON on this machine's
// disk, synchronous_commit=on; SQLite with synchronous=NORMAL, mapd's default.
//
//   storage_ingest_bench [--batches 20000] [--features 20] [--group 64]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "common/postgres.h"
#include "common/temp_dir.h"
#include "storage/support/observation_backends.h"

namespace {

using mapd::Status;
using mapd::StatusOr;
using namespace mapd::storage;

struct Figures {
  double batches_per_s = 0, p50_ms = 0, p99_ms = 0, max_ms = 0;
};

Figures Run(mapd::storage::testing::ObservationBackend& backend, int batches, int features,
            int group) {
  mapd::geometry::SensorObservation f;
  for (int i = 0; i < features; ++i) f.lines.push_back({{0.1 * i, 0, 0}, {0.1 * i + 1, 0.5, 0}});
  std::vector<double> commit_ms;
  const auto start = std::chrono::steady_clock::now();
  uint64_t seq = 0;
  for (int done = 0; done < batches; done += group) {
    const auto t0 = std::chrono::steady_clock::now();
    Status s = backend.Write([&](ObservationWriter& w) {
      std::vector<NewObservation> rows;
      for (int k = 0; k < group && done + k < batches; ++k) {
        NewObservation o;
        o.robot = "r" + std::to_string(k % 8);
        o.session = "s";
        o.seq = ++seq;
        o.features = &f;
        rows.push_back(o);
      }
      // As mapd's writer: the group in one call (one round trip on PostgreSQL).
      return w.InsertObservations(rows).status();
    });
    if (!s.ok()) {
      std::fprintf(stderr, "write failed: %s\n", s.ToString().c_str());
      std::exit(1);
    }
    commit_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::sort(commit_ms.begin(), commit_ms.end());
  Figures out;
  out.batches_per_s = batches / seconds;
  out.p50_ms = commit_ms[commit_ms.size() / 2];
  out.p99_ms = commit_ms[std::min(commit_ms.size() - 1, commit_ms.size() * 99 / 100)];
  out.max_ms = commit_ms.back();
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int batches = 20000, features = 20, group = 64;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--batches")) batches = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--features")) features = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--group")) group = std::atoi(argv[i + 1]);
  }
  std::string why;
  std::unique_ptr<mapd::testing::PostgresCluster> cluster =
      mapd::testing::PostgresCluster::Start(/*fsync=*/true, &why);
  if (cluster == nullptr) {
    std::fprintf(stderr, "no PostgreSQL: %s\n", why.c_str());
    return 1;
  }
  std::printf("%d batches of %d lines, %d per transaction, one writer\n", batches, features, group);
  std::printf("%-12s %12s %10s %10s %10s\n", "backend", "batches/s", "p50 ms", "p99 ms", "max ms");
  mapd::storage::testing::SqliteObservationBackend sqlite;
  mapd::storage::testing::PostgresObservationBackend postgres(cluster->NewDatabase(), "bench");
  for (auto [name, backend] :
       {std::pair<const char*, mapd::storage::testing::ObservationBackend*>{"sqlite", &sqlite},
        {"postgresql", &postgres}}) {
    Status s = backend->Reopen();
    if (!s.ok()) {
      std::fprintf(stderr, "%s: %s\n", name, s.ToString().c_str());
      return 1;
    }
    const Figures f = Run(*backend, batches, features, group);
    std::printf("%-12s %12.0f %10.2f %10.2f %10.2f\n", name, f.batches_per_s, f.p50_ms, f.p99_ms,
                f.max_ms);
  }
  return 0;
}
