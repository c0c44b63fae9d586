#!/usr/bin/env bash
# Lists the tests a ctest run skipped, with the reason each printed, and with
# --strict fails when one is not on the allow-list (tests/skips-allowed.txt).
# ctest counts a skip as a pass ("100% tests passed"), so without this a test
# whose prerequisite is missing (shared data, a tool, a capability) would pass
# CI unnoticed.
# Usage: deploy/check-skips.sh [--strict] JUNIT_XML   (ctest --output-junit)
set -euo pipefail
cd "$(dirname "$0")/.."
strict=0
if [ "${1:-}" = "--strict" ]; then
  strict=1
  shift
fi
junit=${1:?usage: deploy/check-skips.sh [--strict] JUNIT_XML}
python3 - "$junit" tests/skips-allowed.txt "$strict" <<'PY'
import fnmatch, re, sys
import xml.etree.ElementTree as ET

junit, allow_file, strict = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
allowed = []  # (glob, reason)
with open(allow_file, encoding="utf-8") as f:
    for line in f:
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        glob, _, reason = line.partition("|")
        if not reason.strip():
            sys.exit(f"check-skips: {allow_file}: '{line}' gives no reason")
        allowed.append((glob.strip(), reason.strip()))

def reason_of(case):
    """The skip message gtest printed ('[  SKIPPED ]' lines), or ctest's own."""
    out = case.findtext("system-out") or ""
    # gtest prints the reason on the lines between "Skipped" and "[  SKIPPED ]".
    m = re.search(r"Skipped\s*\n(.*?)\n\s*\[\s+SKIPPED", out, re.S)
    if m and m.group(1).strip():
        return " ".join(m.group(1).split())
    lines = [l.strip() for l in out.splitlines() if "skip" in l.lower()]
    if lines:
        return lines[-1][:200]
    skipped = case.find("skipped")
    return (skipped.get("message") if skipped is not None else None) or "no reason printed"

cases = ET.parse(junit).getroot().iter("testcase")
skips = [c for c in cases if c.get("status") in ("skipped", "notrun", "disabled")]
bad = []
for c in skips:
    name = c.get("name")
    rule = next((r for g, r in allowed if fnmatch.fnmatchcase(name, g)), None)
    mark = f"allowed: {rule}" if rule else "NOT ALLOWED"
    print(f"check-skips: skipped {name}: {reason_of(c)} ({mark})")
    if rule is None:
        bad.append(name)
if not skips:
    print("check-skips: no test skipped")
elif bad and strict:
    print(f"check-skips: {len(bad)} skipped test(s) are not on {allow_file}; install what they "
          "need or, if the skip is right on every CI machine, add it there with the reason")
    sys.exit(1)
PY
