"""mapd_client: a Python client of mapd (the mapserver.v1 gRPC API).

    from mapd_client import connect, MapClient, RobotClient, pb

    channel = connect("127.0.0.1:50051")
    with RobotClient(channel) as robot:    # resends what is unacknowledged after a reconnect
        robot.send(batch)                  # a pb.ObservationBatch
    walls = MapClient(channel).feature_map().features
    with MapClient(channel).watch() as feed:   # the change feed; LiveFeatureMap applies it
        for delta in feed: ...

With several mapd on one database (docs/scale-out.md), give RobotClient the
other instances' addresses and MapClient a connect function: they find each
map's owner (redirects, LocateMap) and follow it when it moves.

A robot's laser scans become line observations with mapd_client.laser
(extract_lines, line_batch: the C++ robot library's extractor, the same lines),
its 3D scans plane observations with mapd_client.planes (extract_planes,
read_cloud, plane_batch: the C++ library through libmapd_robot_c).

The stubs (mapserver.v1.map_service_pb2, _pb2_grpc) are generated at build
time into <build>/client/python; see the "Python" section of the project README.
"""

from mapd_client._proto import pb, pb_grpc
from mapd_client.map_client import FeatureMap, MapClient, MapNotServed, connect
from mapd_client.robot_client import (ROBOT_CHANNEL_OPTIONS, IngestCounts, IngestError,
                                      Rejection, RobotClient, robot_channel)
from mapd_client.watch import FeatureWatch, LiveFeatureMap

__all__ = ["pb", "pb_grpc", "connect", "MapClient", "MapNotServed", "FeatureMap", "RobotClient",
           "IngestCounts",
           "IngestError", "Rejection", "FeatureWatch", "LiveFeatureMap", "robot_channel",
           "ROBOT_CHANNEL_OPTIONS"]
