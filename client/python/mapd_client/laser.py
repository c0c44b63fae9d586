"""Line observations from a 2D laser scan, as the C++ robot library makes them
(client/robot/laser_lines.h, docs/robot-library.md): the same split-and-merge,
settings, checks and error messages, in plain Python (no numpy).

    from mapd_client.laser import LaserScan, extract_lines, line_batch

    scan = LaserScan(angle_min_rad=msg.angle_min, angle_increment_rad=msg.angle_increment,
                     range_min_m=msg.range_min, range_max_m=msg.range_max,
                     ranges_m=list(msg.ranges))
    lines = extract_lines(scan)                       # sensor frame, beam order
    batch = line_batch("robot-7", "s1", seq, stamp_ns, (x, y, 0.0), (qw, qx, qy, qz), lines)
    robot.send(batch)

A beam is a return when range_min_m < r < range_max_m; NaN, inf and readings at
or beyond range_max_m end a run. Bad input raises ValueError naming the field.
The lines equal the C++ library's to rounding (tests/client/python/test_laser.py
compares them on every scan of the shared CARMEN logs through `mapctl replay
--export`); about 1 ms a 180-beam scan in CPython here.
"""

import math
from dataclasses import dataclass
from typing import List, Optional, Sequence, Tuple

from mapd_client._proto import pb

_MAX_RANGE_M = 100_000.0
_REFERENCE = (math.cos(0.3), math.sin(0.3))  # geometry::CanonicalDirection's


@dataclass
class LaserScan:
    """One scan as sensor_msgs/LaserScan carries it; angles_rad, when given, one per range."""
    angle_min_rad: float = 0.0
    angle_increment_rad: float = 0.0
    range_min_m: float = 0.0
    range_max_m: float = 0.0
    ranges_m: Sequence[float] = ()
    angles_rad: Optional[Sequence[float]] = None


@dataclass
class LineExtractionParams:
    """robot::LineExtractionParams: the real-log benchmark's defaults."""
    split_m: float = 0.05
    min_points: int = 6
    min_length_m: float = 0.3
    max_gap_m: float = 0.5
    gap_per_range: float = 0.0

    def validate(self) -> None:
        _check(0 < self.split_m <= 10, "line extraction split_m", self.split_m, "(0, 10] m")
        _check(2 <= self.min_points <= 100_000, "line extraction min_points", self.min_points,
               "[2, 100000]")
        _check(0 <= self.min_length_m <= 1000, "line extraction min_length_m",
               self.min_length_m, "[0, 1000] m")
        _check(0 < self.max_gap_m <= 1000, "line extraction max_gap_m", self.max_gap_m,
               "(0, 1000] m")
        _check(0 <= self.gap_per_range <= 10, "line extraction gap_per_range",
               self.gap_per_range, "[0, 10] m per m")


@dataclass
class ExtractedLine:
    a: Tuple[float, float]   # ends in the sensor frame, metres
    b: Tuple[float, float]
    first: int               # first and last beam of the line
    last: int
    rms_m: float = 0.0       # RMS orthogonal distance of its points


def _number(x) -> str:
    s = "%f" % x if isinstance(x, float) and math.isfinite(x) else str(x)
    if "." in s:
        s = s.rstrip("0").rstrip(".")
    return s


def _check(ok: bool, name: str, value, allowed: str) -> None:
    if not ok:
        raise ValueError(f"{name} is {_number(value)}, allowed: {allowed}")


def _check_scan(scan: LaserScan) -> None:
    if len(scan.ranges_m) == 0:
        raise ValueError("scan.ranges_m is empty: no beams")
    _check(math.isfinite(scan.range_min_m) and scan.range_min_m >= 0, "scan.range_min_m",
           scan.range_min_m, "finite, >= 0")
    _check(scan.range_max_m > scan.range_min_m and scan.range_max_m <= _MAX_RANGE_M,
           "scan.range_max_m", scan.range_max_m, "above range_min_m and at most 100000 m")
    if scan.angles_rad is None or len(scan.angles_rad) == 0:
        _check(math.isfinite(scan.angle_min_rad), "scan.angle_min_rad", scan.angle_min_rad,
               "finite")
        _check(math.isfinite(scan.angle_increment_rad) and scan.angle_increment_rad != 0,
               "scan.angle_increment_rad", scan.angle_increment_rad,
               "finite and not 0 (or give angles_rad)")
    else:
        if len(scan.angles_rad) != len(scan.ranges_m):
            raise ValueError(f"scan.angles_rad has {len(scan.angles_rad)} angles for "
                             f"{len(scan.ranges_m)} ranges: give one per range, or none")
        for i, a in enumerate(scan.angles_rad):
            _check(math.isfinite(a), f"scan.angles_rad[{i}]", a, "finite")
    for i, r in enumerate(scan.ranges_m):
        _check(not r < 0, f"scan.ranges_m[{i}]", r, ">= 0, or NaN / inf for no return")


def _farthest_from_chord(pts, first: int, last: int) -> Tuple[int, float]:
    ax, ay = pts[first]
    dx, dy = pts[last][0] - ax, pts[last][1] - ay
    length = math.sqrt(dx * dx + dy * dy)
    best, best_m = first, -1.0
    for i in range(first + 1, last):
        rx, ry = pts[i][0] - ax, pts[i][1] - ay
        dist = abs(dx * ry - dy * rx) / length if length > 0 else math.sqrt(rx * rx + ry * ry)
        if dist > best_m:
            best, best_m = i, dist
    return best, best_m


def _canonical(ux: float, uy: float) -> Tuple[float, float]:
    along = ux * _REFERENCE[0] + uy * _REFERENCE[1]
    if along > 0:
        return ux, uy
    if along < 0:
        return -ux, -uy
    normal = (-_REFERENCE[1], _REFERENCE[0])
    return (ux, uy) if ux * normal[0] + uy * normal[1] >= 0 else (-ux, -uy)


def _fit(pts, first: int, last: int):
    """geometry::PointMoments2 (Welford) and FitLine: centroid, direction, scatter."""
    n = 0
    mx = my = sxx = sxy = syy = 0.0
    for i in range(first, last + 1):
        n += 1
        dx, dy = pts[i][0] - mx, pts[i][1] - my
        mx += dx / n
        my += dy / n
        f = (n - 1.0) / n
        sxx += f * (dx * dx)
        sxy += f * (dx * dy)
        syy += f * (dy * dy)
    theta = 0.5 * math.atan2(2.0 * sxy, sxx - syy)
    ux, uy = _canonical(math.cos(theta), math.sin(theta))
    return (mx, my), (ux, uy), (sxx, sxy, syy), n


def extract_lines(scan: LaserScan,
                  params: Optional[LineExtractionParams] = None) -> List[ExtractedLine]:
    """robot::ExtractLines: the scan's lines in the sensor frame, in beam order."""
    params = params or LineExtractionParams()
    params.validate()
    _check_scan(scan)
    nan = float("nan")
    pts = []
    for i, r in enumerate(scan.ranges_m):
        if not scan.range_min_m < r < scan.range_max_m:
            pts.append((nan, nan))
            continue
        angle = (scan.angle_min_rad + i * scan.angle_increment_rad
                 if scan.angles_rad is None or len(scan.angles_rad) == 0 else scan.angles_rad[i])
        pts.append((r * math.cos(angle), r * math.sin(angle)))

    def finite(p):
        return math.isfinite(p[0]) and math.isfinite(p[1])

    def continues(p, q) -> bool:
        if not finite(q):
            return False
        rng = max(math.sqrt(p[0] * p[0] + p[1] * p[1]), math.sqrt(q[0] * q[0] + q[1] * q[1]))
        limit = params.max_gap_m + params.gap_per_range * rng
        dx, dy = q[0] - p[0], q[1] - p[1]
        return math.sqrt(dx * dx + dy * dy) <= limit

    # Steps 1 and 2: runs without gaps, each split (the break point in both pieces).
    pieces, run_of = [], []
    start, run = 0, 0
    while start < len(pts):
        if not finite(pts[start]):
            start += 1
            continue
        end = start
        while end + 1 < len(pts) and continues(pts[end], pts[end + 1]):
            end += 1
        stack = [(start, end)]
        while stack:
            first, last = stack.pop()
            if last - first >= 2:
                k, dist = _farthest_from_chord(pts, first, last)
                if dist > params.split_m:
                    stack.append((k, last))
                    stack.append((first, k))
                    continue
            pieces.append((first, last))
            run_of.append(run)
        run += 1
        start = end + 1
    # Step 3: merge neighbours of one run while the joined piece stays straight.
    merged = []
    for i, piece in enumerate(pieces):
        if merged and run_of[i] == run_of[i - 1]:
            joined = (merged[-1][0], piece[1])
            if _farthest_from_chord(pts, joined[0], joined[1])[1] <= params.split_m:
                merged[-1] = joined
                continue
        merged.append(piece)
    # Step 4: fit (total least squares), clip to the extreme projections, filter.
    lines = []
    for first, last in merged:
        if last - first + 1 < params.min_points:
            continue
        (px, py), (ux, uy), (sxx, sxy, syy), n = _fit(pts, first, last)
        ts = [(pts[i][0] - px) * ux + (pts[i][1] - py) * uy for i in range(first, last + 1)]
        t_min, t_max = min(ts), max(ts)
        a = (px + t_min * ux, py + t_min * uy)
        b = (px + t_max * ux, py + t_max * uy)
        if math.sqrt((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2) < params.min_length_m:
            continue
        half_trace = 0.5 * (sxx + syy)
        radius = math.hypot(0.5 * (sxx - syy), sxy)
        lines.append(ExtractedLine(a, b, first, last,
                                   math.sqrt(max(0.0, half_trace - radius) / n)))
    return lines


def line_batch(robot_id: str, session_id: str, seq: int, stamp_ns: int,
               translation: Sequence[float], rotation_wxyz: Sequence[float],
               lines: Sequence[ExtractedLine],
               frame: int = pb.SESSION_FRAME_MAP) -> "pb.ObservationBatch":
    """robot::LineBatch: the batch of one scan's lines (z = 0) seen from the sensor
    pose (translation in metres, unit quaternion w, x, y, z) in the session frame."""
    if not robot_id:
        raise ValueError("robot_id is empty")
    if not session_id:
        raise ValueError("session_id is empty")
    if seq < 1:
        raise ValueError("seq is 0: sequence numbers start at 1")
    values = list(translation) + list(rotation_wxyz)
    if len(values) != 7 or not all(math.isfinite(v) for v in values):
        raise ValueError("T_frame_sensor is not finite (translation x, y, z; rotation w, x, y, z)")
    w, x, y, z = rotation_wxyz
    if abs(math.sqrt(w * w + x * x + y * y + z * z) - 1) > 1e-6:
        raise ValueError("T_frame_sensor's rotation is not a unit quaternion")
    batch = pb.ObservationBatch(robot_id=robot_id, session_id=session_id, seq=seq,
                                stamp_ns=stamp_ns, session_frame=frame)
    t = batch.T_frame_sensor
    t.translation.x, t.translation.y, t.translation.z = translation
    t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z = rotation_wxyz
    for i, line in enumerate(lines):
        ends = line.a + line.b
        if not all(math.isfinite(v) for v in ends) or line.a == line.b:
            raise ValueError(f"lines[{i}] is not finite or has no length")
        out = batch.lines.add()
        out.a.x, out.a.y = line.a
        out.b.x, out.b.y = line.b
    return batch


__all__ = ["LaserScan", "LineExtractionParams", "ExtractedLine", "extract_lines", "line_batch"]
