"""mapd_client against a real mapd (conftest.py starts one per test)."""

import math
import subprocess
import time

import grpc
import pytest

import octomap_bt
from mapd_client import IngestError, MapClient, RobotClient, connect, pb

WALLS = [((0, 0), (10, 0)), ((10, 0), (10, 8)), ((10, 8), (0, 8)), ((0, 8), (0, 0))]


def room_batch(robot, session, seq, x, y, yaw=0.0, frame=pb.SESSION_FRAME_MAP):
    """The 10 m x 8 m room's walls seen from (x, y, yaw), in the sensor frame."""
    batch = pb.ObservationBatch(robot_id=robot, session_id=session, seq=seq,
                                stamp_ns=seq * 100_000_000, session_frame=frame)
    pose = batch.T_frame_sensor
    pose.translation.x, pose.translation.y = x, y
    pose.rotation.w, pose.rotation.z = math.cos(yaw / 2), math.sin(yaw / 2)
    c, s = math.cos(yaw), math.sin(yaw)
    for (ax, ay), (bx, by) in WALLS:
        dx, dy = bx - ax, by - ay
        line = batch.lines.add()
        for end, (px, py) in ((line.a, (ax + 0.05 * dx, ay + 0.05 * dy)),
                              (line.b, (bx - 0.05 * dx, by - 0.05 * dy))):
            end.x = c * (px - x) + s * (py - y)
            end.y = -s * (px - x) + c * (py - y)
    return batch


def walk(robot, n, first_seq=1, session="s1"):
    return [room_batch(robot, session, first_seq + i, 2.0 + 0.3 * i, 4.0, 0.1 * i)
            for i in range(n)]


def test_streams_batches_and_reads_the_fused_map(mapd):
    channel = connect(mapd.address)
    with RobotClient(channel) as robot:
        for batch in walk("r1", 20):
            robot.send(batch)
    counts = robot.counts()
    assert (counts.sent, counts.stored, counts.duplicate, counts.rejected) == (20, 20, 0, 0)

    client = MapClient(channel)
    assert client.stats().batches == 20
    assert [r.robot_id for r in client.robots()] == ["r1"]
    fused = client.feature_map(max_wait_ms=5000)
    assert fused.fusion_pending == 0
    assert fused.map_version >= 20
    assert len(fused.features) == 4  # one per wall
    for f in fused.features:
        assert list(f.robots) == ["r1"]
        assert f.support >= 3
    # Only the walls meeting a box around the y = 0 wall.
    bottom = client.feature_map(bbox=(4.0, -0.5, 6.0, 0.5)).features
    assert len(bottom) == 1
    assert abs(bottom[0].a.y) < 0.05 and abs(bottom[0].b.y) < 0.05

    trails = client.trails()
    assert len(trails) == 1 and trails[0].frame_tied and len(trails[0].poses) == 20
    assert trails[0].poses[19].position.x == pytest.approx(2.0 + 0.3 * 19)


def test_resends_what_a_crash_left_unacknowledged(mapd):
    channel = connect(mapd.address)
    robot = RobotClient(channel, give_up_after_s=60)
    batches = walk("r1", 40)
    for batch in batches[:20]:
        robot.send(batch)
    assert robot.wait_for_acks(10)
    mapd.kill()  # a crash: the stream breaks
    for batch in batches[20:]:
        robot.send(batch)  # kept: no stream to take them
    assert robot.unacknowledged() == 20
    mapd.start(listen=mapd.address)  # the same port, the same database
    robot.finish(timeout_s=60)
    counts = robot.counts()
    assert counts.reconnects >= 1
    assert counts.stored + counts.duplicate == 40
    assert counts.rejected == 0
    # Each batch stored once: nothing lost, nothing twice.
    assert MapClient(connect(mapd.address)).stats().batches == 40


def test_duplicates_count_as_acknowledged(mapd):
    channel = connect(mapd.address)
    with RobotClient(channel) as first:
        for batch in walk("r1", 5):
            first.send(batch)
    with RobotClient(channel) as again:  # a robot that restarted and resends
        for batch in walk("r1", 7):
            again.send(batch)
    assert again.counts().duplicate == 5
    assert again.counts().stored == 2
    assert again.unacknowledged() == 0


def test_a_rejected_batch_is_reported_and_the_rest_stored(mapd):
    batches = walk("r1", 3)
    batches[1].lines[2].a.x = float("nan")
    with RobotClient(connect(mapd.address)) as robot:
        for batch in batches:
            robot.send(batch)
    assert robot.counts().stored == 2
    [rejection] = robot.rejections()
    assert (rejection.seq, rejection.code) == (2, grpc.StatusCode.INVALID_ARGUMENT)
    assert "lines[2].a.x" in rejection.message


def test_gives_up_when_the_server_never_comes(tmp_path):
    channel = connect("127.0.0.1:1")  # nothing listens there
    robot = RobotClient(channel, give_up_after_s=1.0)
    robot.send(room_batch("r1", "s1", 1, 1.0, 1.0))
    with pytest.raises(IngestError) as error:
        robot.finish(timeout_s=10)
    assert error.value.code == grpc.StatusCode.UNAVAILABLE
    assert robot.unacknowledged() == 1


def write_room(path, x_min, x_max, shift=(0, 0)):
    """A crop of a furnished room (keys x in [x_min, x_max)), moved by `shift` voxels."""
    boxes = [(5, 5, 14, 10, 6), (20, 28, 26, 40, 9), (33, 8, 45, 14, 4), (45, 30, 52, 36, 12),
             (12, 33, 16, 38, 10)]
    occupied, free = octomap_bt.room(60, 48, 20, boxes)
    crop = lambda keys: [(i + shift[0], j + shift[1], k) for i, j, k in keys if x_min <= i < x_max]
    path.write_bytes(octomap_bt.write_bt(crop(occupied), crop(free), 0.1))
    return str(path)


def test_submaps_upload_list_fetch_and_merge(mapd, tmp_path, with_voxel):
    client = MapClient(connect(mapd.address))
    a = client.upload_submap(write_room(tmp_path / "room_a.bt", 0, 40), robot_id="r1")
    b = client.upload_submap(write_room(tmp_path / "room_b.bt", 20, 60, shift=(-20, 5)),
                             robot_id="r2", name="crop")
    assert (a.name, a.robot_id, b.name) == ("room_a", "r1", "crop")
    assert a.resolution == pytest.approx(0.1)
    assert a.occupied_voxels > 1000 and a.free_voxels > 1000
    assert [m.id for m in client.list_submaps()] == [a.id, b.id]
    assert [m.id for m in client.list_submaps(robot_id="r2")] == [b.id]
    info, data = client.get_submap(a.id)
    assert info.id == a.id and data == (tmp_path / "room_a.bt").read_bytes()

    with pytest.raises(grpc.RpcError) as error:
        client.global_map()
    assert error.value.code() == grpc.StatusCode.NOT_FOUND
    with pytest.raises(grpc.RpcError) as error:
        client.upload_submap_bytes(pb.SubmapHeader(robot_id="r1", name="bad",
                                                   format=pb.SUBMAP_FORMAT_OCTOMAP_BT),
                                   b"not an octree")
    assert error.value.code() == grpc.StatusCode.INVALID_ARGUMENT

    stages = []
    if not with_voxel:
        with pytest.raises(grpc.RpcError) as error:
            client.merge([a.id, b.id])
        assert error.value.code() == grpc.StatusCode.UNIMPLEMENTED
        return
    # Proposed first: no global map until approved (a and b have no session).
    result = client.merge([a.id, b.id], progress=lambda stage, f: stages.append(stage),
                          review=True)
    assert "corners" in stages and "fusion" in stages
    assert result.state == pb.MERGE_STATE_PROPOSED
    assert [m.id for m in client.list_merges(pb.MERGE_STATE_PROPOSED)] == [result.merge_id]
    with pytest.raises(grpc.RpcError) as error:
        client.global_map()
    assert error.value.code() == grpc.StatusCode.NOT_FOUND
    assert client.approve_merge(result.merge_id).state == pb.MERGE_STATE_ACCEPTED
    assert client.get_merge(result.merge_id).state == pb.MERGE_STATE_ACCEPTED
    [aligned_b] = [x for x in result.alignments if x.submap_id == b.id]
    # B's frame is A's moved by (-2.0, +0.5) m: B maps into A by the opposite.
    assert aligned_b.T_reference_submap.translation.x == pytest.approx(2.0, abs=0.15)
    assert aligned_b.T_reference_submap.translation.y == pytest.approx(-0.5, abs=0.15)
    info, data = client.global_map()
    assert info.robot_id == "@global" and data.startswith(b"# Octomap OcTree binary")
    _, about, _ = client.global_map_info()
    assert about.version == 1 and [m.submap_id for m in about.members] == [a.id, b.id]


def test_a_refused_token_gives_up_at_once_and_a_good_one_streams(mapd):
    assert mapd.stop() == 0
    made = subprocess.run([mapd.binary, "token", "create", "--db", mapd.db, "--role", "robot",
                           "--name", "r1-key", "--robot", "r1"],
                          capture_output=True, text=True, check=True)
    token = made.stdout.strip().splitlines()[-1]
    assert token.startswith("mapd_")
    mapd.start(listen=mapd.address)
    channel = connect(mapd.address)

    robot = RobotClient(channel, give_up_after_s=60)  # no token
    robot.send(room_batch("r1", "s1", 1, 1.0, 1.0))
    started = time.monotonic()
    with pytest.raises(IngestError) as error:
        robot.finish(timeout_s=60)
    assert error.value.code == grpc.StatusCode.UNAUTHENTICATED
    assert time.monotonic() - started < 10  # not retried for a minute

    with RobotClient(channel, token=token) as robot:
        robot.send(room_batch("r1", "s1", 1, 1.0, 1.0))
    assert robot.counts().stored == 1
    with pytest.raises(grpc.RpcError) as denied:
        MapClient(channel, token=token).merge([1, 2])
    assert denied.value.code() == grpc.StatusCode.PERMISSION_DENIED


def test_several_maps_each_its_own(tmp_path):
    """mapd --data-dir: a map made from Python, written by a robot and read
    back apart from the default map; a map the server lacks is refused."""
    import os
    from conftest import Mapd
    from mapd_client import MapNotServed
    (tmp_path / "maps").mkdir()
    server = Mapd(os.environ["MAPD_BINARY"], str(tmp_path))
    server.start(extra=("--db", "", "--data-dir", str(tmp_path / "maps")))
    try:
        channel = connect(server.address)
        admin = MapClient(channel)
        assert admin.create_map("site-1").map_id == "site-1"
        with RobotClient(channel, map_id="site-1") as robot:
            for batch in walk("r1", 20):
                robot.send(batch)
        assert robot.counts().stored == 20
        site = MapClient(channel, map_id="site-1")
        assert site.stats().batches == 20
        assert len(site.feature_map(max_wait_ms=5000).features) == 4
        assert admin.stats().batches == 0  # the default map
        assert [m.map_id for m in admin.maps().maps] == ["default", "site-1"]

        # Archived: served no more, kept; restored as it was.
        fused = site.feature_map(max_wait_ms=5000).features
        assert "archive" in admin.delete_map("site-1").where
        assert [m.map_id for m in admin.maps().maps] == ["default"]
        assert [m.map_id for m in admin.maps(archived=True).maps] == ["site-1"]
        with pytest.raises(MapNotServed):
            MapClient(channel, map_id="site-1").stats()
        assert admin.restore_map("site-1").map_id == "site-1"
        assert MapClient(channel, map_id="site-1").feature_map(max_wait_ms=5000).features == fused
        with pytest.raises(grpc.RpcError) as refused:
            admin.delete_map("default")
        assert refused.value.code() == grpc.StatusCode.FAILED_PRECONDITION

        with pytest.raises(MapNotServed, match="does not serve map 'site-2'"):
            MapClient(channel, map_id="site-2").stats()
        lost = RobotClient(channel, map_id="site-2", give_up_after_s=5)
        lost.send(walk("r1", 1)[0])
        with pytest.raises(IngestError) as error:
            lost.finish(timeout_s=10)
        assert error.value.code == grpc.StatusCode.NOT_FOUND
        lost.close()
    finally:
        server.kill()
