#!/usr/bin/env bash
# Runs every fuzz target for SECONDS (default 60) from its seed corpus
# (tests/fuzz/corpus/<target>, read only: new inputs go to BUILD/fuzz-out).
# Exits non-zero when a target crashes, leaks, times out or trips a sanitizer;
# the input is then in BUILD/fuzz-out/crash-* etc. Build first:
#   CC=clang-14 CXX=clang++-14 cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=Debug \
#     -DMAPD_BUILD_FUZZ=ON -DMAPD_WITH_VOXEL=OFF -DMAPD_BUILD_TESTS=OFF -DMAPD_BUILD_BENCH=OFF
#   cmake --build build-fuzz -j2
# Usage: tests/fuzz/run.sh [SECONDS] [BUILD] [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds="${1:-60}"
build="${2:-build-fuzz}"
shift $(( $# > 2 ? 2 : $# ))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(octree_reader ingest_batch config)
# The targets run side by side (each is one process): on CI's two cores three
# targets take SECONDS of wall time instead of three times that.
fuzz_one() {  # fuzz_one TARGET: runs it, prints its summary, returns its status
  local t=$1 out="$build/fuzz-out/$1"
  mkdir -p "$out/corpus"
  # -timeout: one input taking over 10 s is a hang; -rss_limit_mb: a blow-up.
  if ! "$build/tests/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$out/" "$out/corpus" "tests/fuzz/corpus/$t" \
      > "$out/log.txt" 2>&1; then
    echo "fuzz_$t FAILED; input and report in $out/"
    tail -60 "$out/log.txt"
    return 1
  fi
}
declare -A pids
for t in "${targets[@]}"; do
  echo "== fuzz_$t: ${seconds} s"
  fuzz_one "$t" > "$build/fuzz-$t.summary" 2>&1 &
  pids[$t]=$!
done
status=0
for t in "${targets[@]}"; do
  wait "${pids[$t]}" || status=1
  out="$build/fuzz-out/$t"
  echo "== fuzz_$t"
  cat "$build/fuzz-$t.summary"
  grep -aE "^#[0-9]+.*(DONE|pulse)" "$out/log.txt" | tail -1 || true
  grep -aE "stat::number_of_executed_units|stat::peak_rss_mb" "$out/log.txt" || true
done
exit $status
