#!/usr/bin/env bash
# The test command: installs what is missing, builds, runs the whole suite.
# Skipped tests are listed with their reasons at the end (ctest counts a skip
# as a pass); MAPD_STRICT_SKIPS=1 (set by .ci/run) fails on any skip that is
# not on tests/skips-allowed.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
bash deploy/install-deps.sh
bash deploy/build.sh
ctest --preset release -j"$(nproc)" --output-junit "$PWD/build/ctest-junit.xml"
bash deploy/check-skips.sh ${MAPD_STRICT_SKIPS:+--strict} build/ctest-junit.xml
# The fuser's CPU guard (tests/bench/fusion_cpu_guard.cc): fused features per
# CPU-second with free-space evidence on, against docs/long-running.md. Run
# here, alone after the suite, not as a ctest: a measurement beside other
# tests on the same cores would be a flaky unit test.
build/tests/bench/fusion_cpu_guard
# The merges' CPU guard (tests/bench/merge_cpu_guard.cc): two real campus
# pairs merged on 2 threads, against docs/voxel-merge.md; it says so and
# passes without the shared maps.
build/tests/bench/merge_cpu_guard
