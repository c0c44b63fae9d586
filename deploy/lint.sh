#!/usr/bin/env bash
# The tree's habits, checked: every C++ file is formatted with .clang-format,
# and the production sources (server/, client/, storage/) pass .clang-tidy.
# Usage: deploy/lint.sh [BUILD_DIR]   (a configured build: its
# compile_commands.json, unity or not; default ./build). Reformat with
#   git ls-files '*.cc' '*.h' | xargs clang-format-14 -i
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
mapfile -t files < <(git ls-files '*.cc' '*.h')
clang-format-14 --dry-run --Werror "${files[@]}"
echo "lint: ${#files[@]} files formatted"

# clang-tidy runs on what the build compiles: in a unity build (CI) each batch
# of production sources is parsed once and its sources are reported through
# .clang-tidy's HeaderFilterRegex; a file-by-file build (deploy/build.sh) gives
# one unit per source. Largest units first, so the last to finish is short.
# In a batch, a using-declaration that only a later source of the batch needs
# is not reported as unused; the file-by-file run (deploy/lint.sh build, after
# deploy/build.sh) reports it.
root=$(pwd)
mapfile -t units < <(python3 - "$build/compile_commands.json" "$root" <<'PY'
import json, os, re, sys
db, root = sys.argv[1], sys.argv[2]
production = re.compile(re.escape(root) + r"/(server|client|storage)/.*\.cc$")
def sources(path):  # what a unit compiles: a unity batch's includes, or itself
    if "/Unity/unity_" not in path:
        return [path]
    with open(path, encoding="utf-8") as f:
        return re.findall(r'^#include "(.+)"$', f.read(), re.M)
units = {}
for entry in json.load(open(db, encoding="utf-8")):
    path = os.path.join(entry["directory"], entry["file"])
    compiled = sources(path)
    if any(production.match(s) for s in compiled):
        units[path] = sum(os.path.getsize(s) for s in compiled)
print("\n".join(sorted(units, key=units.get, reverse=True)))
PY
)
log=$build/clang-tidy.log
if ! printf '%s\n' "${units[@]}" | xargs -P"$(nproc)" -n1 clang-tidy-14 --quiet \
    --config-file="$root/.clang-tidy" -p "$build" > "$log" 2>&1; then
  grep -E "(error|warning): " "$log" | grep -v "warnings generated" | sort -u
  echo "lint: clang-tidy found the problems above (full log: $log)"
  exit 1
fi
echo "lint: clang-tidy clean (${#units[@]} units)"
