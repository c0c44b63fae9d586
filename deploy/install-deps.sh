#!/usr/bin/env bash
# Installs the Debian 12 packages mapd needs to build and test. Idempotent:
# runs apt-get only when something is missing. --ci adds what .ci/run needs
# beyond that: clang and its libFuzzer runtime (ASan and fuzz jobs), lld (links
# every CI build), Ninja (CI's generator), clang-format and clang-tidy (lint
# job), systemd (systemd-analyze verify of deploy/mapd.service).
# --demo installs only what deploy/demo.sh builds: mapd and mapctl without
# voxel merging, so no PCL (with VTK, Qt, Boost, MPI: 290 MB), no FFTW, no
# GoogleTest, no Python, no Chromium.
# --build-only (the container's build stage, which builds mapd and mapctl
# with MAPD_WITH_ROBOT_PLANES=OFF) leaves out PCL (the robot library's plane
# extractor, the LiDAR simulator, the merge benchmark's FPFH baseline; mapd
# and mapctl do not link it) and what only the tests use: Chromium, which runs the web view's page in tests/web, and the openssl
# tool, which makes the TLS tests' certificates (tests/service/tls_auth_test.cc),
# prometheus, whose promtool checks /metrics (tests/web/web_server_test.cc),
# python3-venv, in which the Python client's test pip-installs it, and
# haproxy, which the rapid-reset test puts in front of mapd with
# deploy/haproxy.cfg (tests/service/rapid_reset_test.cc), and postgresql-15,
# whose server the PostgreSQL storage tests start in a temporary directory
# (tests/common/postgres.h; libpq-dev, the client library, is a build need).
set -euo pipefail

# What mapd and mapctl need without voxel merging (--demo stops here).
PACKAGES=(
  build-essential cmake pkg-config
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libeigen3-dev libsqlite3-dev libpq-dev liboctomap-dev
  libcairo2-dev nlohmann-json3-dev libcli11-dev libcpp-httplib-dev
)
if [ "${1:-}" != "--demo" ]; then
  PACKAGES+=(libfftw3-dev libgtest-dev libgmock-dev
             python3-grpcio python3-protobuf python3-pytest)
fi
if [ "${1:-}" != "--build-only" ] && [ "${1:-}" != "--demo" ]; then
  PACKAGES+=(libpcl-dev chromium openssl prometheus python3-venv haproxy postgresql-15)
fi
if [ "${1:-}" = "--ci" ]; then
  PACKAGES+=(clang-14 libclang-rt-14-dev lld ninja-build clang-format-14 clang-tidy-14 systemd)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
