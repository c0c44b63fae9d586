"""A PEP 517 build backend for mapd_client that needs no download.

pip builds in an isolated environment and installs the backend's requirements
from an index first; robots and CI machines are often offline, so the backend
is this file (no requirements) and writes the wheel itself: mapd_client/*.py
plus the stubs generated from proto/mapserver/v1/map_service.proto. Only
wheels are built (pip installs a local directory from a wheel).
"""
import base64
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # client/python
PROTO_ROOT = os.environ.get("MAPD_PROTO_DIR", os.path.join(HERE, "..", "..", "proto"))
PROTO = "mapserver/v1/map_service.proto"
NAME = "mapd_client"


def _version():
    """The project's version, from the top CMakeLists.txt (one source of truth)."""
    try:
        with open(os.path.join(HERE, "..", "..", "CMakeLists.txt"), encoding="utf-8") as f:
            match = re.search(r"project\(mapd VERSION ([0-9.]+)", f.read())
            return match.group(1) if match else "0"
    except OSError:
        return "0"


def _metadata():
    return (f"Metadata-Version: 2.1\nName: {NAME}\nVersion: {_version()}\n"
            "Summary: Python client of mapd, the multi-robot map server (mapserver.v1 gRPC API)\n"
            "Requires-Python: >=3.9\nRequires-Dist: grpcio\nRequires-Dist: protobuf\n")


def _generate_stubs(out_dir):
    """map_service_pb2(_grpc).py into out_dir/mapserver/v1; a clear error without a generator."""
    proto = os.path.join(PROTO_ROOT, PROTO)
    if not os.path.exists(proto):
        raise RuntimeError(f"mapd_client: {proto} not found; build from a checkout of mapd "
                           "(or set MAPD_PROTO_DIR to its proto/ folder)")
    args = [f"--proto_path={PROTO_ROOT}", f"--python_out={out_dir}", f"--grpc_python_out={out_dir}",
            proto]
    try:
        import grpc_tools.protoc  # pylint: disable=import-outside-toplevel
        if grpc_tools.protoc.main(["protoc"] + args) != 0:
            raise RuntimeError("mapd_client: grpc_tools.protoc failed on " + proto)
        return
    except ImportError:
        pass
    protoc, plugin = shutil.which("protoc"), shutil.which("grpc_python_plugin")
    if not protoc or not plugin:
        raise RuntimeError("mapd_client: generating the gRPC stubs needs grpc_tools "
                           "(pip's grpcio-tools) or protoc and grpc_python_plugin "
                           "(Debian: apt-get install protobuf-compiler-grpc)")
    subprocess.run([protoc, f"--plugin=protoc-gen-grpc_python={plugin}"] + args, check=True)


def _record_line(arcname, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{arcname},sha256={digest},{len(data)}"


def get_requires_for_build_wheel(config_settings=None):  # pylint: disable=unused-argument
    return []


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):  # pylint: disable=unused-argument
    dist_info = f"{NAME}-{_version()}.dist-info"
    os.makedirs(os.path.join(metadata_directory, dist_info), exist_ok=True)
    with open(os.path.join(metadata_directory, dist_info, "METADATA"), "w", encoding="utf-8") as f:
        f.write(_metadata())
    return dist_info


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):  # pylint: disable=unused-argument
    version = _version()
    dist_info = f"{NAME}-{version}.dist-info"
    files = {}
    package = os.path.join(HERE, NAME)
    for name in sorted(os.listdir(package)):
        if name.endswith(".py"):
            with open(os.path.join(package, name), "rb") as f:
                files[f"{NAME}/{name}"] = f.read()
    with tempfile.TemporaryDirectory() as tmp:
        _generate_stubs(tmp)
        for root, _, names in os.walk(tmp):
            for name in sorted(names):
                if name.endswith(".py"):
                    path = os.path.join(root, name)
                    with open(path, "rb") as f:
                        files[os.path.relpath(path, tmp).replace(os.sep, "/")] = f.read()
    files[f"{dist_info}/METADATA"] = _metadata().encode()
    files[f"{dist_info}/WHEEL"] = (b"Wheel-Version: 1.0\nGenerator: mapd_build\n"
                                   b"Root-Is-Purelib: true\nTag: py3-none-any\n")
    record = [_record_line(arcname, data) for arcname, data in files.items()]
    record.append(f"{dist_info}/RECORD,,")
    files[f"{dist_info}/RECORD"] = ("\n".join(record) + "\n").encode()
    wheel_name = f"{NAME}-{version}-py3-none-any.whl"
    with zipfile.ZipFile(os.path.join(wheel_directory, wheel_name), "w",
                         zipfile.ZIP_DEFLATED) as wheel:
        for arcname, data in files.items():
            wheel.writestr(arcname, data)
    return wheel_name


if __name__ == "__main__":  # python3 _build/mapd_build.py DIR: a wheel without pip
    print(build_wheel(sys.argv[1] if len(sys.argv) > 1 else "."))
