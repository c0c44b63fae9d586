"""mapd_client.laser: the C++ robot library's line extraction in Python. The
same lines as the C++ library on the same scans (through `mapctl replay
--export`, which streams scans through it), the walls of a room, bad input
named, and a batch a mapd stores."""

import math
import os
import subprocess
import time

import pytest

from mapd_client import RobotClient, connect, pb
from mapd_client.laser import LaserScan, LineExtractionParams, extract_lines, line_batch


def corridor_log(scans: int) -> str:
    """A CARMEN log of a robot driving along a corridor (walls at y = +-1.5 m)
    that turns a corner at x = 6 m (a wall across it), 180 beams."""
    out = "# corridor\n"
    for k in range(scans):
        x, y, theta = 0.09 * k, 0.1 * math.sin(k / 5), 0.05 * math.sin(k / 7)
        ranges = []
        for i in range(180):
            a = theta - math.pi / 2 + i * math.pi / 180
            c, s = math.cos(a), math.sin(a)
            r = 80.0
            if s > 1e-9:
                r = min(r, (1.5 - y) / s)
            if s < -1e-9:
                r = min(r, (-1.5 - y) / s)
            if c > 1e-9:
                r = min(r, (6.0 - x) / c)
            ranges.append(r)
        t = 1700000000.0 + 0.1 * k
        out += ("FLASER 180 " + " ".join("%.3f" % r for r in ranges) +
                f" {x:.6f} {y:.6f} {theta:.6f} {x:.6f} {y:.6f} {theta:.6f} {t:.6f} host {t:.6f}\n")
    return out


def read_flaser(path: str):
    """The FLASER lines of a plain or gzip CARMEN log: (ranges, x, y, theta)."""
    import gzip  # pylint: disable=import-outside-toplevel
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as f:
        for line in f:
            if not line.startswith("FLASER "):
                continue
            fields = line.split()
            n = int(float(fields[1]))
            yield [float(v) for v in fields[2:2 + n]]


def exported_lines(mapctl: str, log: str, tmp_path) -> list:
    """The lines the C++ library made of each scan of `log` (mapctl replay --export)."""
    out = tmp_path / "batches.jsonl"
    subprocess.run([mapctl, "replay", "--session", "t", "--export", str(out), log], check=True,
                   capture_output=True)
    from google.protobuf import json_format  # pylint: disable=import-outside-toplevel
    batches = [json_format.Parse(line, pb.ObservationBatch()) for line in out.read_text().splitlines()]
    return [[((l.a.x, l.a.y), (l.b.x, l.b.y)) for l in b.lines] for b in batches]


def python_lines(ranges) -> list:
    scan = LaserScan(angle_min_rad=-math.pi / 2, angle_increment_rad=math.pi / len(ranges),
                     range_max_m=80.0, ranges_m=ranges)
    return [(l.a, l.b) for l in extract_lines(scan)]


def compare(mapctl: str, log: str, tmp_path) -> tuple:
    want = exported_lines(mapctl, log, tmp_path)
    start = time.process_time()
    got = [python_lines(r) for r in read_flaser(log)]
    cpu_s = time.process_time() - start
    assert len(got) == len(want)
    differ, worst = 0, 0.0
    for g, w in zip(got, want):
        if len(g) != len(w):
            differ += 1
            continue
        for (ga, gb), (wa, wb) in zip(g, w):
            worst = max(worst, *(abs(p - q) for p, q in zip(ga + gb, wa + wb)))
    return len(got), sum(len(w) for w in want), differ, worst, cpu_s


@pytest.fixture(name="mapctl")
def fixture_mapctl() -> str:
    binary = os.environ.get("MAPCTL_BINARY", "")
    assert os.path.exists(binary), "ctest sets MAPCTL_BINARY"
    return binary


def test_the_cpp_librarys_lines_on_a_generated_log(mapctl, tmp_path):
    log = tmp_path / "corridor.log"
    log.write_text(corridor_log(60))
    scans, lines, differ, worst, _ = compare(mapctl, str(log), tmp_path)
    assert scans == 60 and lines >= 120
    assert differ == 0 and worst < 1e-9, (differ, worst)


def test_the_cpp_librarys_lines_on_the_shared_logs(mapctl, tmp_path):
    shared = os.environ.get("MAPD_SHARED_DIR", "")
    logs = [os.path.join(shared, "data", "laser", name)
            for name in ("intel-corrected.log.gz", "aces-corrected.log.gz")]
    logs = [log for log in logs if os.path.exists(log)]
    if not logs:
        pytest.skip("no CARMEN logs under $MAPD_SHARED_DIR/data/laser")
    for log in logs:
        scans, lines, differ, worst, cpu_s = compare(mapctl, log, tmp_path)
        print(f"{os.path.basename(log)}: {scans} scans, {lines} lines, {differ} differ, "
              f"worst end {worst:.1e} m, Python {1e3 * cpu_s / scans:.2f} ms a scan")
        assert differ == 0 and worst < 1e-9, (log, differ, worst)


def test_bad_input_is_named():
    good = LaserScan(angle_min_rad=0, angle_increment_rad=0.01, range_max_m=10,
                     ranges_m=[1.0] * 10)
    assert extract_lines(good) == []  # 10 points on an arc of 5 deg: 8.7 cm, too short
    cases = [
        (LaserScan(range_max_m=10, angle_increment_rad=0.01), None, "scan.ranges_m is empty"),
        (LaserScan(range_max_m=10, angle_increment_rad=0.01, ranges_m=[1, -2]), None,
         "scan.ranges_m[1] is -2"),
        (LaserScan(range_max_m=10, ranges_m=[1.0]), None, "scan.angle_increment_rad is 0"),
        (LaserScan(range_max_m=0, angle_increment_rad=0.01, ranges_m=[1.0]), None,
         "scan.range_max_m"),
        (LaserScan(range_max_m=10, ranges_m=[1.0, 2.0], angles_rad=[0.0]), None,
         "scan.angles_rad has 1 angles for 2 ranges"),
        (good, LineExtractionParams(split_m=0), "split_m is 0"),
        (good, LineExtractionParams(min_points=1), "min_points is 1"),
    ]
    for scan, params, message in cases:
        with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("]", r"\]")):
            extract_lines(scan, params)


def test_a_scans_batch_is_stored(mapd):
    lines = python_lines([min(80.0, 2.0 / abs(math.cos(-math.pi / 2 + i * math.pi / 180)))
                          if abs(math.cos(-math.pi / 2 + i * math.pi / 180)) > 1e-9 else 80.0
                          for i in range(180)])
    assert len(lines) == 1  # the wall 2 m ahead
    from mapd_client.laser import ExtractedLine  # pylint: disable=import-outside-toplevel
    batch = line_batch("py-robot", "s1", 1, 1_700_000_000_000_000_000, (1.0, 2.0, 0.0),
                       (1.0, 0.0, 0.0, 0.0), [ExtractedLine(a, b, 0, 0) for a, b in lines])
    assert batch.lines[0].a.x == pytest.approx(2.0)
    with RobotClient(connect(mapd.address)) as robot:
        robot.send(batch)
    assert robot.counts().stored == 1
    with pytest.raises(ValueError, match="seq is 0"):
        line_batch("r", "s", 0, 0, (0, 0, 0), (1, 0, 0, 0), [])
    with pytest.raises(ValueError, match="unit quaternion"):
        line_batch("r", "s", 1, 0, (0, 0, 0), (2, 0, 0, 0), [])
