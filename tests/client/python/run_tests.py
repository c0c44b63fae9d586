"""Runs the mapd_client pytest suite for ctest.

Exit 77 (ctest: skipped) with the reason when Debian's python3-grpcio,
python3-protobuf or python3-pytest is missing; any other failure fails.
"""
import importlib
import sys


def main() -> int:
    missing = []
    for module, package in (("grpc", "python3-grpcio"), ("google.protobuf", "python3-protobuf"),
                            ("pytest", "python3-pytest")):
        try:
            importlib.import_module(module)
        except ImportError:
            missing.append(package)
    if missing:
        print("SKIPPED: the Python client tests need " + ", ".join(missing) +
              " (bash deploy/install-deps.sh installs them)")
        return 77
    import pytest  # pylint: disable=import-outside-toplevel
    return pytest.main([sys.argv[1], "-q", "-p", "no:cacheprovider"])


if __name__ == "__main__":
    sys.exit(main())
