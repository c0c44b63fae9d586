"""Runs the mapd_client pytest suite for ctest.

Exit 77 (ctest: skipped) with the reason when Debian's python3-grpcio,
python3-protobuf, python3-pytest or python3-venv (the install test) is missing, or when mapd was not built (a
build of selected targets, like CI's tsan job); any other failure fails.
"""
import importlib
import os
import sys


def main() -> int:
    missing = []
    for module, package in (("grpc", "python3-grpcio"), ("google.protobuf", "python3-protobuf"),
                            ("pytest", "python3-pytest"), ("ensurepip", "python3-venv")):
        try:
            importlib.import_module(module)
        except ImportError:
            missing.append(package)
    if missing:
        print("SKIPPED: the Python client tests need " + ", ".join(missing) +
              " (bash deploy/install-deps.sh installs them)")
        return 77
    binary = os.environ.get("MAPD_BINARY", "")
    if not os.path.exists(binary):
        print(f"SKIPPED: mapd is not built in this tree ({binary or 'MAPD_BINARY unset'})")
        return 77
    import pytest  # pylint: disable=import-outside-toplevel
    return pytest.main([sys.argv[1], "-q", "-p", "no:cacheprovider"])


if __name__ == "__main__":
    sys.exit(main())
