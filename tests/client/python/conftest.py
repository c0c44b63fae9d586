"""A real mapd per test: a temporary database, a free loopback port
(--listen 127.0.0.1:0, the address read from its log), stopped afterwards.
MAPD_BINARY names the binary (ctest sets it)."""

import os
import re
import signal
import subprocess
import sys
import time

import pytest

sys.path.insert(0, os.path.dirname(__file__))  # octomap_bt


class Mapd:
    def __init__(self, binary: str, directory: str):
        self.binary = binary
        self.db = os.path.join(directory, "map.db")
        self.log_path = os.path.join(directory, "mapd.log")
        self.process = None
        self.address = ""

    def start(self, listen: str = "127.0.0.1:0", extra=()) -> str:
        """Starts mapd and returns its address. A restart on a port it had
        (a crash test) retries for up to 10 s while the port is taken: the
        port was an ephemeral one, and between the crash and the restart a
        client's reconnect (a TCP self-connect) or another test's socket may
        hold it for a moment."""
        deadline = time.monotonic() + 10
        while True:
            try:
                return self._start_once(listen, extra)
            except RuntimeError as e:
                if (listen.endswith(":0") or "address in use" not in str(e)
                        or time.monotonic() > deadline):
                    raise
                time.sleep(0.2)

    def _start_once(self, listen: str, extra) -> str:
        log = open(self.log_path, "ab")
        start_at = log.tell()
        self.process = subprocess.Popen(
            [self.binary, "--db", self.db, "--listen", listen, *extra],
            stdout=log, stderr=subprocess.STDOUT)
        log.close()
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            with open(self.log_path, "rb") as f:
                f.seek(start_at)
                m = re.search(rb"event=serving address=(\S+)", f.read())
            if m:
                self.address = m.group(1).decode()
                return self.address
            if self.process.poll() is not None:
                break
            time.sleep(0.02)
        with open(self.log_path, "rb") as f:
            f.seek(start_at)
            this_run = f.read().decode(errors="replace")
        raise RuntimeError("mapd did not come up:\n" + this_run)

    def kill(self) -> None:
        """SIGKILL: a crash, nothing drained."""
        if self.process is not None and self.process.poll() is None:
            self.process.send_signal(signal.SIGKILL)
            self.process.wait()

    def stop(self) -> int:
        if self.process is None or self.process.poll() is not None:
            return self.process.returncode if self.process else 0
        self.process.send_signal(signal.SIGTERM)
        return self.process.wait(timeout=60)

    def log(self) -> str:
        with open(self.log_path, "rb") as f:
            return f.read().decode(errors="replace")


@pytest.fixture
def mapd(tmp_path):
    binary = os.environ.get("MAPD_BINARY")
    if not binary or not os.path.exists(binary):
        pytest.fail("MAPD_BINARY must name the mapd binary (ctest sets it)")
    server = Mapd(binary, str(tmp_path))
    server.start()
    yield server
    server.kill()


@pytest.fixture
def with_voxel() -> bool:
    return os.environ.get("MAPD_WITH_VOXEL", "0") == "1"
