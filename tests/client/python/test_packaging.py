"""mapd_client as a user installs and runs it: `pip install ./client/python`
offline into a virtual environment, and the examples driven by MAPD_SERVER /
MAPD_TOKEN / MAPD_MAP with one-line errors (issue 43 item 9)."""

import os
import socket
import subprocess
import sys

PYTHON_DIR = os.path.join(os.path.dirname(__file__), "..", "..", "..", "client", "python")
EXAMPLES = os.path.join(PYTHON_DIR, "examples")


def run_example(name, *args, env=None):
    full_env = dict(os.environ)
    for key in ("MAPD_SERVER", "MAPD_TOKEN", "MAPD_MAP"):
        full_env.pop(key, None)
    full_env.update(env or {})
    return subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args],
                          capture_output=True, text=True, env=full_env, timeout=120, check=False)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_pip_installs_it_offline_with_its_stubs(tmp_path):
    venv = tmp_path / "venv"
    made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)],
                          capture_output=True, text=True, check=False)
    assert made.returncode == 0, "python3 -m venv (Debian: python3-venv): " + made.stderr
    pip = subprocess.run([str(venv / "bin" / "pip"), "install", "--no-index",
                          os.path.abspath(PYTHON_DIR)],
                         capture_output=True, text=True, check=False, timeout=300,
                         env={**os.environ, "PIP_INDEX_URL": "http://127.0.0.1:9/"})
    assert pip.returncode == 0, pip.stdout + pip.stderr
    # Outside the source tree and without PYTHONPATH: what pip installed.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    probe = subprocess.run(
        [str(venv / "bin" / "python"), "-c",
         "import mapd_client; print(mapd_client.__file__); "
         "print(mapd_client.pb.ObservationBatch.DESCRIPTOR.full_name)"],
        capture_output=True, text=True, cwd=tmp_path, env=env, check=False)
    assert probe.returncode == 0, probe.stderr
    assert str(venv) in probe.stdout
    assert "mapserver.v1.ObservationBatch" in probe.stdout
    assert not os.path.exists(os.path.join(PYTHON_DIR, "build")), "pip left a build folder"


def test_the_examples_follow_the_environment(mapd):
    done = run_example("stream_robot.py", "--scans", "5", "--period", "0",
                       env={"MAPD_SERVER": mapd.address})
    assert done.returncode == 0, done.stderr
    assert "5 stored" in done.stdout
    shown = run_example("feature_map.py", env={"MAPD_SERVER": mapd.address})
    assert shown.returncode == 0, shown.stderr
    assert "5 batches" in shown.stdout


def test_errors_are_one_line_not_a_traceback(mapd):
    nobody = f"127.0.0.1:{free_port()}"
    for name in ("feature_map.py", "stream_robot.py"):
        args = ("--scans", "1", "--give-up-after", "1") if name == "stream_robot.py" else ()
        r = run_example(name, *args, env={"MAPD_SERVER": nobody})
        assert r.returncode == 1, (name, r.stdout, r.stderr)
        assert "Traceback" not in r.stderr, r.stderr
        assert r.stderr.count("\n") == 1, r.stderr
        assert r.stderr.startswith(name + ": UNAVAILABLE"), r.stderr
    other_map = run_example("feature_map.py", env={"MAPD_SERVER": mapd.address,
                                                   "MAPD_MAP": "site7"})
    assert other_map.returncode == 1
    assert "map 'site7'" in other_map.stderr and "serves one map" in other_map.stderr
    refused = run_example("feature_map.py", env={"MAPD_SERVER": mapd.address,
                                                 "MAPD_TOKEN": "mapd_1_bogus"})
    assert refused.returncode == 1
    assert refused.stderr.startswith("feature_map.py: UNAUTHENTICATED"), refused.stderr
