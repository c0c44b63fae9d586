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
log=$build/clang-tidy.log
# A unity build lists only its batches; clang-tidy parses each source alone,
# so a missing include in production code fails here whatever the build.
python3 deploy/per-file-compile-db.py "$build" "$build/per-file" > /dev/null
if ! run-clang-tidy-14 -p "$build/per-file" -quiet -j"$(nproc)" "$(pwd)/(server|client|storage)/.*\.cc$" > "$log" 2>&1; then
  grep -E "(error|warning): " "$log" | grep -v "warnings generated" | sort -u
  echo "lint: clang-tidy found the problems above (full log: $log)"
  exit 1
fi
echo "lint: clang-tidy clean ($(grep -c '^clang-tidy' "$log") files)"
