#!/usr/bin/env python3
"""Follows the fused map live (WatchFeatureMap): one line per complete change.

    python3 client/python/examples/watch_map.py       # mapd at $MAPD_SERVER

It reconnects by itself when mapd restarts (from the last complete
map_version); Ctrl-C ends it.
"""
import argparse

from mapd_client import LiveFeatureMap, MapClient, connect
from mapd_client.cli import add_connection_arguments, check_map, run_main


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_connection_arguments(parser)
    parser.add_argument("--bbox", type=float, nargs=4, metavar=("XMIN", "YMIN", "XMAX", "YMAX"))
    parser.add_argument("--robot", default="", help="only what this robot contributed to")
    args = parser.parse_args()
    check_map(args.map)

    live = LiveFeatureMap()
    with MapClient(connect(args.server), token=args.token).watch(
            bbox=args.bbox, robot_id=args.robot) as feed:
        try:
            resync = False  # a resync may span several messages (more = true)
            for delta in feed:
                resync = resync or delta.resync
                if live.apply(delta):
                    print(f"map version {live.map_version}: {len(live.features)} walls, "
                          f"{len(live.planes)} planes{' (resync)' if resync else ''}", flush=True)
                    resync = False
        except KeyboardInterrupt:
            pass  # leaving the `with` cancels the watch


if __name__ == "__main__":
    run_main(main)
