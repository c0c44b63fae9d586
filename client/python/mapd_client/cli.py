"""What a command-line tool on mapd_client needs, as the examples use it.

    parser = argparse.ArgumentParser()
    add_connection_arguments(parser)        # --server, --token, --map from MAPD_*
    args = parser.parse_args()
    run_main(lambda: work(args))            # errors as one line, exit 1

The environment is the same as mapctl's: MAPD_SERVER (host:port), MAPD_TOKEN
(a bearer token: better there than on the command line, which every user of
the machine can read in /proc) and MAPD_MAP.
"""
import argparse
import os
import sys
from typing import Callable, Optional

import grpc

from mapd_client.robot_client import IngestError

DEFAULT_SERVER = "127.0.0.1:50051"


def add_connection_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--server", default=os.environ.get("MAPD_SERVER") or DEFAULT_SERVER,
                        help="mapd's address, host:port (default $MAPD_SERVER or %(default)s)")
    parser.add_argument("--token", default=os.environ.get("MAPD_TOKEN", ""),
                        help="a bearer token (default $MAPD_TOKEN, the safer place for it)")
    parser.add_argument("--map", default=os.environ.get("MAPD_MAP", ""),
                        help="the map (default $MAPD_MAP); this mapd serves one map, 'default'")


def check_map(name: str) -> None:
    """This mapd serves one map: refuse another name at once rather than write
    one site's data into another's map."""
    if name not in ("", "default"):
        raise ValueError(f"map '{name}' (--map or $MAPD_MAP): this mapd serves one map, "
                         "'default'; leave MAPD_MAP unset")


def describe(error: BaseException) -> str:
    """One line for an error a user can act on."""
    if isinstance(error, grpc.RpcError):
        code = error.code()
        return f"{code.name if code else 'UNKNOWN'}: {error.details()}"
    if isinstance(error, IngestError):
        return f"{error.code.name}: {error.message}"
    return str(error)


def run_main(main: Callable[[], Optional[int]], prog: Optional[str] = None) -> None:
    """Runs `main` and exits with its code; an RPC, ingest, file or argument
    error is printed as `prog: ...` on one line and exits 1, Ctrl-C exits 130."""
    prog = prog or os.path.basename(sys.argv[0])
    try:
        code = main()
    except KeyboardInterrupt:
        sys.exit(130)
    except (grpc.RpcError, IngestError, OSError, ValueError) as error:
        print(f"{prog}: {describe(error)}", file=sys.stderr)
        sys.exit(1)
    sys.exit(code or 0)
