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
