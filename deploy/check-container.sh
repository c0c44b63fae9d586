#!/usr/bin/env bash
# The container image as an operator runs it (CI job "container"), with
# Debian's podman, no Docker engine and no registry:
#   1. a Debian 12 base image made with debootstrap and imported (once per
#      machine: localhost/debian:bookworm);
#   2. deploy/Containerfile's runtime stage (--target runtime: its packages,
#      user, entrypoint, config, health check), plus the binaries of BUILD_DIR
#      instead of a second compile of the whole tree (the build stage is
#      deploy/build.sh, which the test job runs);
#   3. the container: mapd comes up as uid 10001 (not root), its health check
#      says SERVING, a simulated robot streams 60 scans through it and every
#      one is stored, the image holds no compiler and no -dev package, and
#      `podman stop` ends mapd cleanly (exit 0, event=stopped).
# Usage: deploy/check-container.sh [BUILD_DIR]   (default build)
# Needs root (podman's rootful mode) and Debian's mirror; installs podman,
# runc and debootstrap when missing.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
for b in "$build/server/mapd/mapd" "$build/server/mapd/mapd-health" "$build/client/mapctl"; do
  [ -x "$b" ] || { echo "check-container: $b is not built"; exit 1; }
done
missing=()
for p in podman runc debootstrap; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" > /dev/null
fi

work=$(mktemp -d)
cid=""
cleanup() {
  [ -n "$cid" ] && podman rm -f -t 2 "$cid" > /dev/null 2>&1 || true
  rm -rf "$work"
}
trap cleanup EXIT
# This machine's quirks (podman 4.3): crun refuses hybrid cgroups, so runc;
# podman's default nofile limit is above the hard limit here.
printf '[containers]\ndefault_ulimits=["nofile=%s:%s","nproc=4096:4096"]\n[engine]\nruntime="runc"\n' \
  "$(ulimit -Hn)" "$(ulimit -Hn)" > "$work/containers.conf"
export CONTAINERS_CONF="$work/containers.conf"

base=localhost/debian:bookworm
if ! podman image exists "$base"; then
  # The Debian mirror apt already uses (not a third-party repository's).
  mirror=$( (cat /etc/apt/sources.list /etc/apt/sources.list.d/* 2>/dev/null || true) \
           | grep -E '^(URIs:|deb) ' | grep -oE 'https?://[^ ]+/debian/?' | head -1 || true)
  echo "check-container: making $base with debootstrap from ${mirror:-deb.debian.org}"
  debootstrap --variant=minbase bookworm "$work/rootfs" "${mirror:-http://deb.debian.org/debian}" \
    > "$work/debootstrap.log" 2>&1 || { tail -20 "$work/debootstrap.log"; exit 1; }
  chroot "$work/rootfs" apt-get clean
  rm -rf "$work/rootfs/var/lib/apt/lists/"*
  tar -C "$work/rootfs" -c . | podman import - "$base" > /dev/null
  rm -rf "$work/rootfs"
fi

podman build -q --format docker --network host --build-arg BASE="$base" --target runtime \
  -t localhost/mapd-runtime -f deploy/Containerfile . > /dev/null
mkdir -p "$work/bin"
cp "$build/server/mapd/mapd" "$build/server/mapd/mapd-health" "$build/client/mapctl" "$work/bin/"
printf 'FROM localhost/mapd-runtime\nCOPY mapd mapd-health mapctl /usr/local/bin/\n' \
  | podman build -q --format docker -t localhost/mapd-ci -f - "$work/bin" > /dev/null
echo "check-container: image built"

port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
# (podman's timed health checks need systemd, which CI machines do not run:
# its complaints go to run.err, and the check runs the HEALTHCHECK's command.)
cid=$(podman run -d --network host -e MAPD_PORT="$port" localhost/mapd-ci 2> "$work/run.err")
for _ in $(seq 300); do
  podman exec "$cid" mapd-entrypoint health > /dev/null 2>&1 && break
  sleep 0.1
done
podman exec "$cid" mapd-entrypoint health | grep -q SERVING \
  || { podman logs "$cid"; echo "check-container: health is not SERVING"; exit 1; }
uid=$(podman exec "$cid" id -u)
[ "$uid" = 10001 ] || { echo "check-container: mapd runs as uid $uid, not 10001 (mapd)"; exit 1; }
dev=$(podman exec "$cid" sh -c "dpkg-query -W -f='\${Package}\n' | grep -E -- '-dev$|^(gcc|g\+\+|cpp|cmake|make)(-[0-9]+)?$' || true")
[ -z "$dev" ] || { echo "check-container: build packages in the image: $dev"; exit 1; }
out=$("$build/client/mapctl" --server "127.0.0.1:$port" simulate --robots 1 --scans 60)
echo "$out" | grep -q "60 stored" || { echo "$out"; echo "check-container: the robot's scans were not stored"; exit 1; }
podman stop -t 30 "$cid" > /dev/null 2>> "$work/run.err"
code=$(podman inspect -f '{{.State.ExitCode}}' "$cid")
podman logs "$cid" 2>&1 | grep -q "event=stopped" || { podman logs "$cid"; echo "check-container: no event=stopped"; exit 1; }
[ "$code" = 0 ] || { podman logs "$cid"; echo "check-container: mapd exited $code"; exit 1; }
echo "check-container: uid $uid, health SERVING, 60 scans stored, no build packages, clean stop"
