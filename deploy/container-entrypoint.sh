#!/bin/sh
# mapd in its container (deploy/Containerfile).
#   - Certificates mounted in $MAPD_TLS_DIR (default /etc/mapd/tls: server.crt,
#     server.key, optionally ca.crt): TLS on all interfaces, port $MAPD_PORT,
#     with auth.required (docs/security.md; first token: podman exec <id>
#     mapd token create --db /var/lib/mapd/map.db --role admin --name root).
#   - No certificates: plaintext on the container's loopback only (mapd refuses
#     plaintext off loopback); reachable with `podman exec`, not from outside.
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
if has_tls; then
  # shellcheck disable=SC2086  # config_args is empty or two words
  exec mapd $config_args --db "$db" --listen "0.0.0.0:$port" \
    --tls_cert "$tls_dir/server.crt" --tls_key "$tls_dir/server.key" --auth.required true "$@"
fi
echo "mapd-entrypoint: no server.crt/server.key in $tls_dir: listening on 127.0.0.1:$port" \
  "only (not reachable from outside the container); mount certificates to serve TLS" >&2
# shellcheck disable=SC2086
exec mapd $config_args --db "$db" --listen "127.0.0.1:$port" "$@"
