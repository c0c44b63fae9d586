"""mapd_client with two mapd on one PostgreSQL (docs/scale-out.md): a robot
given one instance finds its map's owner through the redirect, and after
the owner is killed (-9) the other instance's takeover; MapClient reaches
the owner through LocateMap, or through forwarding without it. Nothing is stored twice or lost."""

import os
import subprocess

import pytest

from conftest import Mapd
from mapd_client import MapClient, RobotClient, connect
from test_mapd_client import walk


def start_instance(tmp_path, store, name, ready):
    directory = tmp_path / name
    directory.mkdir()
    server = Mapd(os.environ["MAPD_BINARY"], str(directory))
    server.start(extra=("--db", "", "--store", store, "--lease_ttl_s", "1",
                        "--instance_name", name), ready=ready)
    return server


def test_a_robot_follows_its_map_to_the_owner_and_over_a_kill(tmp_path, postgres):
    store = postgres.new_database()
    a = start_instance(tmp_path, store, "mapd-a", ready="serving")
    b = start_instance(tmp_path, store, "mapd-b", ready="listening")
    try:
        MapClient(connect(a.address)).create_map("site-1")
        owner = MapClient(connect(a.address), map_id="site-1").locate()
        assert owner.live and owner.address in (a.address, b.address)
        other = b.address if owner.address == a.address else a.address

        # Asked at the instance that does not serve it: the call is forwarded
        # to the owner and answered (a stream of batches is redirected, below).
        assert MapClient(connect(other), map_id="site-1", timeout_s=5).robots() == []

        # A robot that knows both addresses but starts at the wrong one.
        robot = RobotClient(connect(other), map_id="site-1", addresses=[owner.address],
                            give_up_after_s=60)
        for batch in walk("r1", 30):
            robot.send(batch)
        assert robot.wait_for_acks(30), robot.counts()
        assert robot.counts().stored == 30
        assert robot.counts().redirects >= 1
        site = MapClient(connect(other), map_id="site-1", connect=connect)
        assert site.robots()[0].batches == 30

        # The owner dies: the other instance takes the map over, the robot
        # resends what was not acknowledged.
        victim = a if owner.address == a.address else b
        victim.kill()
        for batch in walk("r1", 30, first_seq=31):
            robot.send(batch)
        robot.finish(timeout_s=60)
        counts = robot.counts()
        assert counts.rejected == 0
        assert counts.stored + counts.duplicate == 60
        survivor = MapClient(connect(other), map_id="site-1", connect=connect)
        assert survivor.locate().address == other
        assert survivor.robots()[0].batches == 60  # each batch stored once
    finally:
        a.kill()
        b.kill()


def test_mapctl_and_the_python_client_agree_on_the_owner(tmp_path, postgres):
    """mapctl given both addresses and MapClient with connect read the same
    map from whichever instance serves it."""
    store = postgres.new_database()
    a = start_instance(tmp_path, store, "mapd-a", ready="serving")
    b = start_instance(tmp_path, store, "mapd-b", ready="listening")
    try:
        MapClient(connect(b.address)).create_map("site-2")
        with RobotClient(connect(b.address), map_id="site-2",
                         addresses=[a.address]) as robot:
            for batch in walk("r2", 10):
                robot.send(batch)
        out = subprocess.run([os.environ["MAPCTL_BINARY"], "--server",
                              f"{a.address},{b.address}", "--map", "site-2", "robots"],
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, out.stderr
        assert "r2" in out.stdout
        for address in (a.address, b.address):
            assert MapClient(connect(address), map_id="site-2",
                             connect=connect).robots()[0].batches == 10
    finally:
        a.kill()
        b.kill()
