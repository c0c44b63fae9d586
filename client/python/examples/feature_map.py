#!/usr/bin/env python3
"""Prints the fused map (walls and planes) and the server's statistics.

    python3 client/python/examples/feature_map.py     # mapd at $MAPD_SERVER
"""
import argparse

from mapd_client import MapClient, connect
from mapd_client.cli import add_connection_arguments, check_map, run_main


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_connection_arguments(parser)
    parser.add_argument("--bbox", type=float, nargs=4, metavar=("XMIN", "YMIN", "XMAX", "YMAX"))
    args = parser.parse_args()
    check_map(args.map)

    client = MapClient(connect(args.server), token=args.token)
    stats = client.stats()
    print(f"mapd {stats.version}: {stats.robots} robots, {stats.batches} batches, "
          f"{stats.fused_features} fused features, {stats.submaps} submaps")
    fused = client.feature_map(bbox=args.bbox)
    print(f"map version {fused.map_version} ({fused.fusion_pending} observations pending)")
    for f in fused.features:
        print(f"  wall {f.id}: ({f.a.x:.2f}, {f.a.y:.2f}) -> ({f.b.x:.2f}, {f.b.y:.2f}) m, "
              f"support {f.support}, robots {','.join(f.robots)}")
    for p in fused.planes:
        print(f"  plane {p.id}: normal ({p.normal.x:.2f}, {p.normal.y:.2f}, {p.normal.z:.2f}), "
              f"{p.area:.1f} m^2, z {p.z_min:.2f}..{p.z_max:.2f} m")


if __name__ == "__main__":
    run_main(main)
