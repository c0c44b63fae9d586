"""MapClient.watch and LiveFeatureMap against a real mapd (conftest.py)."""

import threading
import time

import grpc
import pytest

from mapd_client import LiveFeatureMap, MapClient, RobotClient, connect
from test_mapd_client import walk


class Watcher(threading.Thread):
    """Applies a watch to a LiveFeatureMap on its own thread; `state()` is
    the last complete (map_version, features, planes)."""

    def __init__(self, feed):
        super().__init__(daemon=True)
        self.feed = feed
        self.live = LiveFeatureMap()
        self.lock = threading.Lock()
        self.snapshot = (0, {}, {})
        self.error = None
        self.resyncs = 0

    def run(self):
        try:
            for delta in self.feed:
                self.resyncs += 1 if delta.resync else 0
                if self.live.apply(delta):
                    with self.lock:
                        self.snapshot = (self.live.map_version, dict(self.live.features),
                                         dict(self.live.planes))
        except Exception as error:  # pylint: disable=broad-except
            self.error = error  # an RpcError, or anything that ended the thread

    def state(self):
        with self.lock:
            return self.snapshot


def ingest(address, batches):
    with RobotClient(connect(address)) as robot:
        for batch in batches:
            robot.send(batch)
    assert robot.counts().stored == len(batches)


def settle(client, watcher, bbox=None, mapd=None):
    """Waits (bounded) for the fuser to be idle and the watch to reach its
    version; returns GetFeatureMap's map then and the watcher's state. On
    timeout it says where the watch stands (and the tail of mapd's log)."""
    deadline = time.monotonic() + 60
    while True:
        fused = client.feature_map(bbox=bbox, max_wait_ms=5000)
        version, features, planes = watcher.state()
        if fused.fusion_pending == 0 and version == fused.map_version:
            return fused, features, planes
        assert watcher.error is None, watcher.error
        if time.monotonic() >= deadline:
            log = ""
            if mapd is not None:
                with open(mapd.log_path, errors="replace") as f:
                    log = "".join(f.readlines()[-40:])
            pytest.fail(f"the watch is at version {version}, the map at {fused.map_version} "
                        f"(fusion pending {fused.fusion_pending}); feed: {watcher.feed.reconnects} "
                        f"reconnects, resume_version {watcher.feed.resume_version}, last error "
                        f"{watcher.feed.last_error!r}, watcher alive {watcher.is_alive()}\n"
                        f"mapd's log:\n{log}")
        time.sleep(0.05)


def assert_same(fused, features, planes):
    assert features == {f.id: f for f in fused.features}
    assert planes == {p.id: p for p in fused.planes}


def test_the_live_map_equals_the_feature_map_at_its_version(mapd):
    client = MapClient(connect(mapd.address))
    batches = walk("r1", 30)
    with client.watch() as everything, client.watch(bbox=(4.0, -0.5, 6.0, 0.5)) as bottom:
        watchers = [Watcher(everything), Watcher(bottom)]
        for watcher in watchers:
            watcher.start()
        for first in range(0, 30, 10):  # three batches of batches, checked after each
            ingest(mapd.address, batches[first:first + 10])
            fused, features, planes = settle(client, watchers[0])
            assert len(features) == 4
            assert_same(fused, features, planes)
            assert_same(*settle(client, watchers[1], bbox=(4.0, -0.5, 6.0, 0.5)))
    for watcher in watchers:
        watcher.join(timeout=30)
        assert not watcher.is_alive() and watcher.error is None  # close() ends it cleanly
    assert len(watchers[1].state()[1]) == 1
    assert watchers[0].resyncs == 1 and everything.reconnects == 0


def test_resumes_after_a_restart_and_ends_equal_to_the_feature_map(mapd):
    client = MapClient(connect(mapd.address))
    ingest(mapd.address, walk("r1", 10))
    feed = client.watch()
    watcher = Watcher(feed)
    watcher.start()
    settle(client, watcher)
    before = feed.resume_version
    assert before > 0
    assert mapd.stop() == 0  # the watch ends with UNAVAILABLE
    # Down for longer than the first backoff (0.5 s): the reconnect finds no
    # server and must wait for it, not hang on a call that failed to connect
    # (it did, under ASan in CI, where mapd restarts slowly).
    time.sleep(1.5)
    mapd.start(listen=mapd.address)  # the same port, the same database
    ingest(mapd.address, walk("r1", 10, first_seq=11) + walk("r2", 10))
    assert_same(*settle(client, watcher, mapd=mapd))
    assert feed.reconnects >= 1 and feed.resume_version > before
    assert feed.last_error.startswith("UNAVAILABLE: "), feed.last_error  # shutdown, or down
    assert {r for f in watcher.state()[1].values() for r in f.robots} == {"r1", "r2"}
    feed.close()
    watcher.join(timeout=30)
    assert not watcher.is_alive() and watcher.error is None


def test_a_bad_filter_is_an_error_naming_the_field(mapd):
    client = MapClient(connect(mapd.address))
    with client.watch(bbox=(5.0, 0.0, 1.0, 1.0)) as feed:
        with pytest.raises(grpc.RpcError) as error:
            next(iter(feed))
    assert error.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "bbox" in error.value.details()
    with pytest.raises(grpc.RpcError) as error:
        next(iter(client.watch(since_map_version=1000)))
    assert error.value.code() == grpc.StatusCode.INVALID_ARGUMENT
    assert "since_map_version" in error.value.details()
    assert client.stats().batches == 0  # the server is still up
