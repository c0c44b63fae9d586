#!/usr/bin/env python3
"""Writes a per-file compile_commands.json for a unity build.

With CMAKE_UNITY_BUILD, CMake lists only its generated unity_N_cxx.cxx batches
in compile_commands.json, so clang-tidy would never parse a source on its own.
Each batch is a list of `#include "/abs/path/file.cc"` lines; this gives every
included source its batch's command with the batch's path replaced by the
source's. A database without unity batches is copied as it is.

Usage: per-file-compile-db.py BUILD_DIR OUT_DIR   (writes OUT_DIR/compile_commands.json)
"""
import json
import os
import re
import sys

INCLUDE = re.compile(r'^#include "(.+)"\s*$')


def expand(entries):
    for entry in entries:
        batch = entry["file"]
        if "/Unity/unity_" not in batch:
            yield entry
            continue
        with open(batch, encoding="utf-8") as f:
            sources = [m.group(1) for m in map(INCLUDE.match, f) if m]
        for source in sources:
            one = dict(entry, file=source)
            if "command" in one:
                one["command"] = one["command"].replace(batch, source)
            if "arguments" in one:
                one["arguments"] = [source if a == batch else a for a in one["arguments"]]
            yield one


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.strip().splitlines()[-1])
    build_dir, out_dir = sys.argv[1], sys.argv[2]
    with open(os.path.join(build_dir, "compile_commands.json"), encoding="utf-8") as f:
        entries = list(expand(json.load(f)))
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "compile_commands.json"), "w", encoding="utf-8") as f:
        json.dump(entries, f, indent=1)
    print(f"per-file-compile-db: {len(entries)} sources")


if __name__ == "__main__":
    main()
