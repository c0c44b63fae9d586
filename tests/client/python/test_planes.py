"""mapd_client.planes: the C++ robot library's plane extraction from Python
(libmapd_robot_c through ctypes). The same planes as `mapctl replay` makes of
the same scan, a room's floor and wall from lists, numpy and files, bad input
named, and a batch a mapd stores."""

import json
import os
import subprocess

import pytest

from mapd_client import RobotClient, connect
from mapd_client.planes import (PlaneExtractionParams, extract_planes, plane_batch,
                                read_cloud)

LIBRARY = os.environ.get("MAPD_ROBOT_LIBRARY", "")
pytestmark = pytest.mark.skipif(
    not os.path.exists(LIBRARY),
    reason="MAPD_ROBOT_LIBRARY unset: built without the plane extractor (MAPD_WITH_ROBOT_PLANES)")


def dense_room():
    """A floor 1 m below the sensor and a wall 4 m ahead, every 10 cm
    (tests/robot/room_scan.h's DenseRoom)."""
    floor = [(0.1 * i, 0.1 * j, -1.0) for i in range(5, 40) for j in range(-30, 31)]
    wall = [(4.0, 0.1 * j, 0.1 * k) for j in range(-30, 31) for k in range(-10, 21)]
    return floor + wall


def near(planes, normal, offset):
    return [p for p in planes
            if sum(a * b for a, b in zip(p.normal, normal)) > 0.9998 and abs(p.offset_m - offset) < 0.02]


def test_the_rooms_floor_and_wall():
    planes = extract_planes(dense_room())
    assert len(planes) == 2
    floor, wall = near(planes, (0, 0, 1), 1.0), near(planes, (-1, 0, 0), 4.0)
    assert len(floor) == 1 and len(wall) == 1
    assert len(floor[0].inliers) >= 35 * 61 and len(wall[0].boundary) >= 3  # and the foot of the wall
    grown = extract_planes(dense_room(), params=PlaneExtractionParams(segmentation="region_growing"))
    assert len(near(grown, (0, 0, 1), 1.0)) == 1


def test_numpy_arrays_are_taken_as_they_are():
    np = pytest.importorskip("numpy")
    planes = extract_planes(np.array(dense_room(), dtype=np.float64))
    assert len(planes) == 2
    with pytest.raises(ValueError, match=r"shape \(4, 2\), expected \(N, 3\)"):
        extract_planes(np.zeros((4, 2)))


def test_the_same_planes_as_mapctl_replay(tmp_path):
    """mapctl replay streams a scan folder through the C++ library; its export
    holds the C++ planes of the same points, which Python must equal."""
    mapctl = os.environ.get("MAPCTL_BINARY", "")
    assert os.path.exists(mapctl), "ctest sets MAPCTL_BINARY"
    folder = tmp_path / "scans"
    folder.mkdir()
    points = dense_room()
    (folder / "0.xyz").write_text("".join(f"{x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in points))
    (folder / "poses.txt").write_text("0 0 0 0 0 0 0 1\n")
    out = subprocess.run([mapctl, "replay", str(folder), "--export", "-"], check=True,
                         capture_output=True, text=True).stdout
    cpp = json.loads(out.splitlines()[0])["planes"]
    python = extract_planes(read_cloud(str(folder / "0.xyz")).points)
    assert len(python) == len(cpp) == 2
    for c, p in zip(cpp, python):
        assert [c["normal"].get(k, 0.0) for k in "xyz"] == pytest.approx(list(p.normal), abs=1e-12)
        assert c.get("offset", 0.0) == pytest.approx(p.offset_m, abs=1e-12)
        assert len(c["boundary"]) == len(p.boundary)


def test_files_and_bad_input_are_named(tmp_path):
    pcd = tmp_path / "room.pcd"
    points = dense_room()
    pcd.write_text("VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                   f"WIDTH {len(points)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                   f"POINTS {len(points)}\nDATA ascii\n" +
                   "".join(f"{x} {y} {z}\n" for x, y, z in points))
    cloud = read_cloud(str(pcd))
    assert len(cloud) == len(points) and (cloud.rows, cloud.columns) == (0, 0)
    assert len(extract_planes(cloud.points)) == 2

    with pytest.raises(FileNotFoundError, match="cannot open point cloud"):
        read_cloud(str(tmp_path / "none.pcd"))
    (tmp_path / "bad.xyz").write_text("1 2 3\n4 5\n")
    with pytest.raises(ValueError, match=r"bad.xyz:2: not an 'x y z' line"):
        read_cloud(str(tmp_path / "bad.xyz"))
    with pytest.raises(ValueError, match=r"distance_m must be in \(0, 1\]"):
        extract_planes(points, params=PlaneExtractionParams(distance_m=0))
    with pytest.raises(ValueError, match=r"the cloud is not rows x columns points \(3 x 3"):
        extract_planes(points, rows=3, columns=3)
    with pytest.raises(ValueError, match=r"points\[1\] has 2 values"):
        extract_planes([(0, 0, 0), (1, 2)])
    with pytest.raises(ValueError, match="segmentation is 'magic'"):
        extract_planes(points, params=PlaneExtractionParams(segmentation="magic"))
    assert extract_planes([]) == []


def test_a_scans_batch_is_stored(mapd):
    planes = extract_planes(dense_room())
    batch = plane_batch("py-lidar", "s1", 1, 1_700_000_000_000_000_000, (1.0, 2.0, 0.5),
                        (1.0, 0.0, 0.0, 0.0), planes)
    assert len(batch.planes) == 2
    with RobotClient(connect(mapd.address)) as robot:
        robot.send(batch)
    assert robot.counts().stored == 1
    planes[0].normal = (2.0, 0.0, 0.0)
    with pytest.raises(ValueError, match=r"planes\[0\].normal is not a unit vector"):
        plane_batch("r", "s", 1, 0, (0, 0, 0), (1, 0, 0, 0), planes)
