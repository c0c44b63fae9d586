#!/usr/bin/env python3
"""Draws docs/architecture.svg from the build's own link graph.

    python3 deploy/architecture_svg.py build > docs/architecture.svg

Asks CMake for the target graph (cmake --graphviz) of the configured build
tree, keeps the production targets (no tests, benchmarks, fuzzers or imported
packages), removes the links implied by others (transitive reduction) and
draws one row per layer, binaries on top, arrows pointing at what a target
links. A target that is in no layer below is drawn in a row of its own and
named on stderr: add it to LAYERS. Needs only Python 3 and CMake.
"""

import os
import re
import subprocess
import sys
import tempfile
from xml.sax.saxutils import escape

# Top to bottom. Each target goes in the first layer that names it.
LAYERS = [
    ("binaries", ["mapd", "mapd_health", "mapctl"]),
    ("front ends", ["mapd_cli", "web", "mapclient"]),
    ("service, pictures", ["service", "maprender", "occupancy_grid"]),
    ("robot", ["maprobot", "robot_planes", "mapd_robot_c", "robot_datasets", "robot_extraction",
               "laser_sim"]),
    ("infrastructure", ["storage", "config", "mapd_proto"]),
    ("algorithms", ["fusion", "voxel"]),
    ("geometry, io", ["geometry", "voxel_io"]),
    ("foundations", ["mapd_common"]),
]
TEST_SIDE = re.compile(
    r"(test|bench|fuzz|diag|guard|throughput|city_sim|lidar_sim|eval|stubs|^gmock|^gtest)", re.I)
# CMake's shapes for what this project defines: executables, static and
# interface libraries (external libraries are "Unknown Library" septagons).
OURS = {"egg", "octagon", "pentagon"}
# Shared libraries are double octagons, like the imported ones (PCL's): ours by name.
OUR_SHARED = {"mapd_robot_c"}

ROW_H, BOX_H, MARGIN, CHAR_W = 92, 34, 20, 7.6


def graph(build: str):
    with tempfile.TemporaryDirectory() as tmp:
        dot = os.path.join(tmp, "deps.dot")
        subprocess.run(["cmake", f"--graphviz={dot}", build], check=True,
                       stdout=subprocess.DEVNULL)
        text = open(dot, encoding="utf-8").read()
    names = {node: label for node, label, shape in
             re.findall(r'"(node\d+)" \[ label = "([^"]+)", shape = (\w+)', text)
             if shape in OURS or label in OUR_SHARED}
    edges = {(names[a], names[b]) for a, b in re.findall(r'"(node\d+)" -> "(node\d+)"', text)
             if a in names and b in names}
    return set(names.values()), edges


def reduce(nodes, edges):
    """Drops a -> c when a reaches c through another target."""
    out = {n: {b for a, b in edges if a == n} for n in nodes}

    def reaches(a, c, skip):
        stack, seen = [b for b in out[a] if (a, b) != skip], set()
        while stack:
            n = stack.pop()
            if n == c:
                return True
            if n not in seen:
                seen.add(n)
                stack.extend(out[n])
        return False
    return {(a, c) for a, c in edges if not reaches(a, c, (a, c))}


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    nodes, edges = graph(sys.argv[1])
    ours = {n for n in nodes if "::" not in n and not n.startswith("-") and "/" not in n
            and not TEST_SIDE.search(n) and not n.endswith(".so")}
    layered = {n for _, names in LAYERS for n in names}
    unknown = sorted(n for n in ours if n not in layered and any(a == n or b == n for a, b in edges))
    for n in unknown:
        print(f"architecture_svg: {n} is in no layer (add it to LAYERS)", file=sys.stderr)
    rows = [(layer, [n for n in names if n in ours]) for layer, names in LAYERS]
    if unknown:
        rows.append(("other", unknown))
    rows = [(layer, names) for layer, names in rows if names]
    drawn = {n for _, names in rows for n in names}
    links = reduce(drawn, {(a, b) for a, b in edges if a in drawn and b in drawn and a != b})

    # Fewer crossings: each row ordered by where its links go (the mean
    # position of the targets it links and is linked by), a few sweeps.
    order = {n: i for _, names in rows for i, n in enumerate(names)}
    for _ in range(4):
        for _, names in rows:
            def centre(n):
                near = [order[b] / max(1, len(r)) for a, b in links if a == n
                        for _, r in rows if b in r] + \
                       [order[a] / max(1, len(r)) for a, b in links if b == n
                        for _, r in rows if a in r]
                return sum(near) / len(near) if near else order[n] / max(1, len(names))
            names.sort(key=centre)
            for i, n in enumerate(names):
                order[n] = i
    width = max(900, max(sum(len(n) * CHAR_W + 40 for n in names) for _, names in rows) + 160)
    height = ROW_H * len(rows) + 60
    box = {}
    for r, (layer, names) in enumerate(rows):
        y = 40 + r * ROW_H
        widths = [len(n) * CHAR_W + 24 for n in names]
        gap = (width - 140 - sum(widths)) / (len(names) + 1)
        x = 140 + gap
        for n, w in zip(names, widths):
            box[n] = (x, y, w)
            x += w + gap
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0f}" height="{height}" '
           f'viewBox="0 0 {width:.0f} {height}" font-family="DejaVu Sans, Arial, sans-serif" '
           'font-size="13">',
           '  <defs><marker id="arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" '
           'markerHeight="7" orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" '
           'fill="#777"/></marker></defs>',
           '  <rect width="100%" height="100%" fill="white"/>',
           f'  <text x="{MARGIN}" y="22" font-size="15" font-weight="bold">mapd: libraries and '
           'what links what (drawn from the build by deploy/architecture_svg.py)</text>']
    for r, (layer, _) in enumerate(rows):
        y = 40 + r * ROW_H + BOX_H / 2 + 4
        out.append(f'  <text x="{MARGIN}" y="{y:.0f}" fill="#666">{escape(layer)}</text>')
    if os.environ.get("ARCHITECTURE_EDGES"):  # the links drawn, for checking
        for a, b in sorted(links):
            print(f"{a} -> {b}", file=sys.stderr)
    for a, b in sorted(links):
        xa, ya, wa = box[a]
        xb, yb, wb = box[b]
        x1, y1 = xa + wa / 2, ya + (BOX_H if yb > ya else 0)
        x2, y2 = xb + wb / 2, yb + (0 if yb > ya else BOX_H)
        out.append(f'  <line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" '
                   'stroke="#999" marker-end="url(#arrow)"/>')
    for n, (x, y, w) in sorted(box.items()):
        out.append(f'  <rect x="{x:.1f}" y="{y}" width="{w:.1f}" height="{BOX_H}" rx="5" '
                   'fill="#eef4fb" stroke="#4a78a8"/>')
        out.append(f'  <text x="{x + w / 2:.1f}" y="{y + BOX_H / 2 + 5:.0f}" '
                   f'text-anchor="middle">{escape(n)}</text>')
    out.append("</svg>")
    print("\n".join(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
