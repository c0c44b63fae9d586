#!/usr/bin/env bash
# Packaging checks that need no container runtime (CI job "package"):
#   1. deploy/mapd.service and deploy/mapd@.service pass `systemd-analyze verify`
#      (on copies whose ExecStart names the built binary, since /usr/local/bin/mapd
#      need not exist);
#   2. every shared library that mapd, mapd-health and mapctl load (ldd) belongs
#      to a Debian package that deploy/Containerfile's runtime stage installs:
#      one of RUNTIME_PACKAGES or a (recursive) dependency of one;
#   3. mapd --version prints the version in CMakeLists.txt;
#   4. the container entrypoint is valid sh.
# Usage: deploy/check-package.sh [BUILD_DIR]   (default build; built with the voxel library)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
bins=("$build/server/mapd/mapd" "$build/server/mapd/mapd-health" "$build/client/mapctl")
for b in "${bins[@]}"; do [ -x "$b" ] || { echo "check-package: $b is not built"; exit 1; }; done
fail=0

# 1. The unit.
unit_dir="$(mktemp -d)"
trap 'rm -rf "$unit_dir"' EXIT
sed "s|/usr/local/bin/mapd |$(realpath "$build/server/mapd/mapd") |" deploy/mapd.service > "$unit_dir/mapd.service"
if out="$(systemd-analyze verify "$unit_dir/mapd.service" 2>&1)" && [ -z "$out" ]; then
  echo "check-package: systemd-analyze verify deploy/mapd.service: ok"
else
  echo "check-package: systemd-analyze verify deploy/mapd.service:"; echo "$out"; fail=1
fi
systemd-analyze security --offline=true "$unit_dir/mapd.service" 2>/dev/null | tail -1 | sed 's/^/check-package: /' || true
# The template for instances on a shared PostgreSQL, as its instance 1.
sed "s|/usr/local/bin/mapd |$(realpath "$build/server/mapd/mapd") |" "deploy/mapd@.service" > "$unit_dir/mapd@1.service"
if out="$(systemd-analyze verify "$unit_dir/mapd@1.service" 2>&1)" && [ -z "$out" ]; then
  echo "check-package: systemd-analyze verify deploy/mapd@.service: ok"
else
  echo "check-package: systemd-analyze verify deploy/mapd@.service:"; echo "$out"; fail=1
fi

# 2. Runtime libraries against the Containerfile.
read -r -a wanted <<< "$(sed -n 's/^ARG RUNTIME_PACKAGES="\(.*\)"$/\1/p' deploy/Containerfile)"
[ ${#wanted[@]} -gt 0 ] || { echo "check-package: no ARG RUNTIME_PACKAGES=\"...\" in deploy/Containerfile"; exit 1; }
declare -A closure=()
queue=("${wanted[@]}")
while [ ${#queue[@]} -gt 0 ]; do
  p="${queue[0]}"; queue=("${queue[@]:1}")
  [ -n "${closure[$p]:-}" ] && continue
  if ! deps="$(dpkg-query -W -f='${Pre-Depends}, ${Depends}' "$p" 2>/dev/null)"; then
    echo "check-package: $p (Containerfile) is not a package installed here"; fail=1; continue
  fi
  closure[$p]=1
  # "a (>= 1), b:any | c" -> a b c
  for d in $(echo "$deps" | tr ',|' '\n\n' | sed 's/(.*)//; s/:any//; s/\s//g' | grep -v '^$'); do
    [ -n "${closure[$d]:-}" ] || queue+=("$d")
  done
done
libs="$(ldd "${bins[@]}" | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u)"
# A library's path as ldd, realpath and the merged /usr may spell it.
spellings() { local real; real="$(realpath "$1")"; echo "$1" "$real" "/usr$1" "/usr$real" "${1#/usr}" "${real#/usr}"; }
# One dpkg -S for every spelling of every library (one call per path took 20 s):
# "pkg[:arch]: /path" for each path a package owns; the rest is not found.
declare -A owner=()
mapfile -t asked < <(for lib in $libs; do spellings "$lib" | tr ' ' '\n'; done | sort -u)
while IFS= read -r line; do
  path="${line#*: }"
  [ -n "${owner[$path]:-}" ] || owner[$path]="${line%%:*}"
done < <(dpkg -S "${asked[@]}" 2>/dev/null || true)
checked=0
for lib in $libs; do
  pkg=""
  for path in $(spellings "$lib"); do
    pkg="${owner[$path]:-}" && [ -n "$pkg" ] && break
  done
  checked=$((checked + 1))
  if [ -z "$pkg" ]; then
    echo "check-package: $lib belongs to no Debian package"; fail=1
  elif [ -z "${closure[$pkg]:-}" ]; then
    echo "check-package: $lib ($pkg) is not installed by deploy/Containerfile's runtime stage"; fail=1
  fi
done
echo "check-package: $checked runtime libraries, ${#wanted[@]} named packages (${#closure[@]} with dependencies)"

# 3. --version.
want="mapd $(sed -n 's/^project(mapd VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)"
got="$("$build/server/mapd/mapd" --version)"
[ "$got" = "$want" ] || { echo "check-package: mapd --version says '$got', want '$want'"; fail=1; }

# 4. The entrypoint.
sh -n deploy/container-entrypoint.sh || fail=1

[ $fail -eq 0 ] && echo "check-package: ok"
exit $fail
