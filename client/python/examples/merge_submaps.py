#!/usr/bin/env python3
"""Uploads OctoMap submaps, merges them and saves the global map.

    python3 client/python/examples/merge_submaps.py a.bt:r1 b.bt:r2 -o world.bt
"""
import argparse
import sys

import grpc

from mapd_client import MapClient, connect
from mapd_client.cli import add_connection_arguments, check_map, describe, run_main


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("submaps", nargs="+", metavar="FILE:ROBOT",
                        help="an OctoMap file (.bt/.ot) and the robot that built it")
    add_connection_arguments(parser)
    parser.add_argument("-o", "--output", default="world.bt")
    args = parser.parse_args()
    check_map(args.map)

    client = MapClient(connect(args.server), token=args.token)
    ids = []
    for item in args.submaps:
        path, _, robot = item.rpartition(":")
        info = client.upload_submap(path, robot_id=robot)
        print(f"submap {info.id}: {info.name} ({info.occupied_voxels} occupied voxels)")
        ids.append(info.id)
    try:
        result = client.merge(ids, progress=lambda stage, f: print(f"  {stage:10s} {100 * f:3.0f}%"))
    except grpc.RpcError as error:  # FAILED_PRECONDITION: too little evidence, with the figure
        print(f"merge refused: {describe(error)}", file=sys.stderr)
        return 1
    for a in result.alignments:
        t = a.T_reference_submap.translation
        print(f"submap {a.submap_id}: at ({t.x:.2f}, {t.y:.2f}, {t.z:.2f}) m, "
              f"{a.matched_corners} corners, residual {a.residual_m:.3f} m")
    info, data = client.global_map()
    with open(args.output, "wb") as out:
        out.write(data)
    print(f"wrote {len(data)} bytes to {args.output} (merged submap {info.id})")
    return 0


if __name__ == "__main__":
    run_main(main)
