#!/bin/sh
# mapd in its container (deploy/Containerfile).
#   - Certificates mounted in $MAPD_TLS_DIR (default /etc/mapd/tls: server.crt,
#     server.key, optionally ca.crt): TLS on all interfaces, port $MAPD_PORT,
#     with auth.required (docs/security.md; first token: podman exec <id>
#     mapd token create --db /var/lib/mapd/map.db --role admin --name root).
#   - No certificates: plaintext on the container's loopback only (mapd refuses
#     plaintext off loopback); reachable with `podman exec`, not from outside.
#   - MAPD_STORE set (a libpq connection string without the password): the
#     maps of that PostgreSQL database instead of $MAPD_DB, with
#     MAPD_ADVERTISE_ADDRESS (host:port clients reach this container at, for
#     redirects) and MAPD_INSTANCE_NAME (stable across restarts) when set; the
#     password from PGPASSWORD or a mounted PGPASSFILE (docs/scale-out.md).
# Arguments given to the container are passed to mapd after ours, so they win
# (e.g. `--fusion.gamma 0.4`). `mapd-entrypoint health` is the HEALTHCHECK:
# grpc.health.v1 through mapd-health, over TLS when mapd serves TLS (checking
# the certificate against ca.crt, else server.crt, for the name $MAPD_TLS_NAME,
# default localhost).
set -eu
tls_dir="${MAPD_TLS_DIR:-/etc/mapd/tls}"
port="${MAPD_PORT:-50051}"
config="${MAPD_CONFIG:-/etc/mapd/mapd.conf}"
db="${MAPD_DB:-/var/lib/mapd/map.db}"

has_tls() { [ -r "$tls_dir/server.crt" ] && [ -r "$tls_dir/server.key" ]; }

if [ "${1:-}" = "health" ]; then
  if has_tls; then
    ca="$tls_dir/ca.crt"
    [ -r "$ca" ] || ca="$tls_dir/server.crt"
    exec mapd-health --server "127.0.0.1:$port" --tls-ca "$ca" --tls-name "${MAPD_TLS_NAME:-localhost}"
  fi
  exec mapd-health --server "127.0.0.1:$port"
fi

config_args=""
[ -r "$config" ] && config_args="--config $config"
# Where the maps live: the positional parameters carry them (they may hold spaces).
user_args_count=$#
if [ -n "${MAPD_STORE:-}" ]; then
  set -- "$@" --store "$MAPD_STORE"
  [ -n "${MAPD_ADVERTISE_ADDRESS:-}" ] && set -- "$@" --advertise_address "$MAPD_ADVERTISE_ADDRESS"
  [ -n "${MAPD_INSTANCE_NAME:-}" ] && set -- "$@" --instance_name "$MAPD_INSTANCE_NAME"
else
  set -- "$@" --db "$db"
fi
# Ours first, the container's arguments last (they win): rotate them to the end.
i=0
while [ "$i" -lt "$user_args_count" ]; do
  first="$1"
  shift
  set -- "$@" "$first"
  i=$((i + 1))
done
if has_tls; then
  # shellcheck disable=SC2086  # config_args is empty or two words
  exec mapd $config_args --listen "0.0.0.0:$port" \
    --tls_cert "$tls_dir/server.crt" --tls_key "$tls_dir/server.key" --auth.required true "$@"
fi
echo "mapd-entrypoint: no server.crt/server.key in $tls_dir: listening on 127.0.0.1:$port" \
  "only (not reachable from outside the container); mount certificates to serve TLS" >&2
# shellcheck disable=SC2086
exec mapd $config_args --listen "127.0.0.1:$port" "$@"
