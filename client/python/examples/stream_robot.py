#!/usr/bin/env python3
"""A robot walking through a 10 m x 8 m room, streaming the walls it sees.

    python3 client/python/examples/stream_robot.py    # mapd at $MAPD_SERVER

Stop mapd in the middle and start it again: the client reconnects and resends
what was not acknowledged; the server stores each batch once.
"""
import argparse
import math
import time

from mapd_client import RobotClient, connect, pb
from mapd_client.cli import add_connection_arguments, check_map, run_main

WALLS = [((0, 0), (10, 0)), ((10, 0), (10, 8)), ((10, 8), (0, 8)), ((0, 8), (0, 0))]


def scan(robot, session, seq, x, y, yaw):
    batch = pb.ObservationBatch(robot_id=robot, session_id=session, seq=seq,
                                stamp_ns=time.time_ns(), session_frame=pb.SESSION_FRAME_MAP)
    pose = batch.T_frame_sensor
    pose.translation.x, pose.translation.y = x, y
    pose.rotation.w, pose.rotation.z = math.cos(yaw / 2), math.sin(yaw / 2)
    c, s = math.cos(yaw), math.sin(yaw)
    for (ax, ay), (bx, by) in WALLS:  # each wall in the sensor frame
        line = batch.lines.add()
        for end, (px, py) in ((line.a, (ax, ay)), (line.b, (bx, by))):
            end.x, end.y = c * (px - x) + s * (py - y), -s * (px - x) + c * (py - y)
    return batch


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_connection_arguments(parser)
    parser.add_argument("--robot", default="py-robot")
    parser.add_argument("--session", default=time.strftime("run-%Y%m%d-%H%M%S"))
    parser.add_argument("--scans", type=int, default=100)
    parser.add_argument("--period", type=float, default=0.05, help="seconds between scans")
    parser.add_argument("--give-up-after", type=float, default=30.0,
                        help="seconds without reaching mapd before giving up")
    args = parser.parse_args()
    check_map(args.map)

    with RobotClient(connect(args.server), token=args.token,
                     give_up_after_s=args.give_up_after) as robot:
        for i in range(args.scans):
            t = i / max(1, args.scans - 1)
            robot.send(scan(args.robot, args.session, i + 1, 1.0 + 8.0 * t, 4.0 + math.sin(6 * t),
                            0.5 * math.sin(3 * t)))
            time.sleep(args.period)
    c = robot.counts()
    print(f"{c.sent} sent: {c.stored} stored, {c.duplicate} duplicate, {c.rejected} rejected, "
          f"{c.reconnects} reconnects")


if __name__ == "__main__":
    run_main(main)
