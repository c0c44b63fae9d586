"""A real mapd per test: a temporary database, a free loopback port
(--listen 127.0.0.1:0, the address read from its log), stopped afterwards.
MAPD_BINARY names the binary (ctest sets it). The `postgres` fixture starts
a throw-away PostgreSQL (Debian's postgresql-15) for tests of several mapd
on one database."""

import glob
import os
import pwd
import re
import shutil
import signal
import subprocess
import sys
import tempfile
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

    def start(self, listen: str = "127.0.0.1:0", extra=(), ready: str = "serving") -> str:
        """Starts mapd and returns its address. A restart on a port it had
        (a crash test) retries for up to 10 s while the port is taken: the
        port was an ephemeral one, and between the crash and the restart a
        client's reconnect (a TCP self-connect) or another test's socket may
        hold it for a moment."""
        deadline = time.monotonic() + 10
        while True:
            try:
                return self._start_once(listen, extra, ready)
            except RuntimeError as e:
                if (listen.endswith(":0") or "address in use" not in str(e)
                        or time.monotonic() > deadline):
                    raise
                time.sleep(0.2)

    def _start_once(self, listen: str, extra, ready: str) -> str:
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
                m = re.search(rb"event=" + ready.encode() + rb" address=(\S+)", f.read())
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


class Postgres:
    """A PostgreSQL cluster in a temporary directory, on a Unix socket only
    (initdb refuses root: as root it runs as the postgres user)."""

    def __init__(self):
        bindirs = sorted(glob.glob("/usr/lib/postgresql/*/bin/pg_ctl"), reverse=True)
        if not bindirs:
            raise FileNotFoundError("PostgreSQL server binaries not found "
                                    "(install postgresql-15)")
        self.bindir = os.path.dirname(bindirs[0])
        self.dir = tempfile.mkdtemp(prefix="mapd-pg-")
        self.run_as = []
        if os.getuid() == 0:
            user = pwd.getpwnam("postgres")
            os.chown(self.dir, user.pw_uid, user.pw_gid)
            self.run_as = ["/usr/sbin/runuser", "-u", "postgres", "--"]
        self.data = os.path.join(self.dir, "data")
        self._run("initdb", "-D", self.data, "-U", "mapd", "-A", "trust", "-E", "UTF8",
                  "--no-sync", "--locale=C")
        self._run("pg_ctl", "-D", self.data, "-l", os.path.join(self.dir, "server.log"), "-o",
                  f"-c listen_addresses='' -k {self.dir} -p 5432 -c max_connections=100",
                  "-w", "-t", "60", "start")
        self._databases = 0

    def _run(self, tool: str, *args: str) -> None:
        subprocess.run(self.run_as + [os.path.join(self.bindir, tool), *args], check=True,
                       capture_output=True, timeout=120)

    def conninfo(self, dbname: str) -> str:
        return f"host={self.dir} port=5432 user=mapd dbname={dbname}"

    def new_database(self) -> str:
        """A new, empty database's connection string."""
        self._databases += 1
        name = f"py{os.getpid()}_{self._databases}"
        self._run("psql", "-h", self.dir, "-p", "5432", "-U", "mapd", "-d", "postgres",
                  "-c", f"CREATE DATABASE {name}")
        return self.conninfo(name)

    def stop(self) -> None:
        subprocess.run(self.run_as + [os.path.join(self.bindir, "pg_ctl"), "-D", self.data,
                                      "-m", "immediate", "-w", "stop"], capture_output=True)
        shutil.rmtree(self.dir, ignore_errors=True)


@pytest.fixture(scope="session")
def postgres():
    """A PostgreSQL for the session. Without one the test skips, unless
    MAPD_STRICT_SKIPS=1 (CI), where it fails: CI runs every PostgreSQL test."""
    try:
        cluster = Postgres()
    except (OSError, KeyError, subprocess.SubprocessError) as error:
        detail = getattr(error, "stderr", b"") or b""
        reason = f"no PostgreSQL for the tests: {error} {detail.decode(errors='replace')}"
        if os.environ.get("MAPD_STRICT_SKIPS") == "1":
            pytest.fail(reason)
        pytest.skip(reason)
    yield cluster
    cluster.stop()
