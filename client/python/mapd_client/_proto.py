"""The generated protobuf and gRPC modules of mapserver.v1.

They are generated at build time (client/python/CMakeLists.txt) into the build
tree, never committed: put <build>/client/python on PYTHONPATH.
"""

try:
    from mapserver.v1 import map_service_pb2 as pb
    from mapserver.v1 import map_service_pb2_grpc as pb_grpc
except ImportError as error:  # pragma: no cover - depends on the environment
    raise ImportError(
        "mapd_client: the generated stubs mapserver.v1.map_service_pb2(_grpc) were not found "
        "(" + str(error) + "). Build the project (cmake --build build) and put "
        "build/client/python on PYTHONPATH beside client/python.") from error

__all__ = ["pb", "pb_grpc"]
