#!/usr/bin/env bash
# Configures and builds mapd, mapctl and the tests (Release) into ./build
# (CMakePresets.json: the release preset; MAPD_CMAKE_ARGS adds -D options).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset release ${MAPD_CMAKE_ARGS:-} > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build --preset release -j"$(nproc)" >> build.log 2>&1 || { tail -50 build.log; exit 1; }
echo "build: ok (log in build.log)"
