"""Plane observations from a 3D scan, through the C++ robot library itself
(client/robot/cloud_planes.h, docs/robot-library.md): its shared C interface
libmapd_robot_c.so (client/robot/c_api.h) loaded with ctypes, so the planes
are the C++ library's, not a re-implementation.

    from mapd_client.planes import extract_planes, read_cloud, plane_batch

    cloud = read_cloud("scan.pcd")              # or points from your driver
    planes = extract_planes(cloud.points, cloud.rows, cloud.columns, wrap_columns=True)
    batch = plane_batch("robot-7", "s1", seq, stamp_ns, (x, y, z), (qw, qx, qy, qz), planes)
    robot.send(batch)

The library is found at $MAPD_ROBOT_LIBRARY, else by the system's search
(`ctypes.util.find_library("mapd_robot_c")`: /usr/local/lib after `cmake
--install`). It is built with the plane extractor (MAPD_WITH_ROBOT_PLANES,
PCL). Points: any sequence of (x, y, z) in metres, sensor frame, or a numpy
array of shape (N, 3); NaN for no return. Bad input raises ValueError with
the C++ library's message.
"""

import ctypes
import ctypes.util
import math
import os
from array import array
from dataclasses import dataclass, field
from typing import List, Optional, Sequence, Tuple

from mapd_client._proto import pb


class _Params(ctypes.Structure):
    _fields_ = [("segmentation", ctypes.c_int), ("distance_m", ctypes.c_double),
                ("max_iterations", ctypes.c_int), ("min_inliers", ctypes.c_uint64),
                ("min_extent_m", ctypes.c_double), ("min_width_m", ctypes.c_double),
                ("min_rows", ctypes.c_int), ("max_rms_m", ctypes.c_double),
                ("max_planes", ctypes.c_int), ("jump_base_m", ctypes.c_double),
                ("jump_factor", ctypes.c_double), ("normal_neighbours", ctypes.c_int),
                ("smoothness_deg", ctypes.c_double), ("max_curvature", ctypes.c_double)]


_lib = None


def _library():
    """The loaded libmapd_robot_c, its functions typed; RuntimeError naming
    where it was looked for when it cannot be found."""
    global _lib
    if _lib is not None:
        return _lib
    path = os.environ.get("MAPD_ROBOT_LIBRARY") or ctypes.util.find_library("mapd_robot_c")
    if not path:
        raise RuntimeError("libmapd_robot_c.so not found: set MAPD_ROBOT_LIBRARY to its path "
                           "(a build's client/robot/libmapd_robot_c.so) or install it "
                           "(cmake --install); it is built with MAPD_WITH_ROBOT_PLANES=ON")
    lib = ctypes.CDLL(path)
    c_size, c_int, c_double = ctypes.c_size_t, ctypes.c_int, ctypes.c_double
    lib.mapd_plane_params_default.argtypes = [ctypes.POINTER(_Params)]
    lib.mapd_plane_params_default.restype = None
    lib.mapd_extract_planes.argtypes = [
        ctypes.c_void_p, c_size, c_int, c_int, c_int, ctypes.POINTER(_Params),
        ctypes.POINTER(ctypes.c_void_p), ctypes.c_char_p, c_size]
    lib.mapd_extract_planes.restype = c_int
    lib.mapd_planes_count.argtypes = [ctypes.c_void_p]
    lib.mapd_planes_count.restype = c_size
    lib.mapd_planes_get.argtypes = [
        ctypes.c_void_p, c_size, ctypes.POINTER(c_double), ctypes.POINTER(c_double),
        ctypes.POINTER(c_double), ctypes.POINTER(c_size), ctypes.POINTER(c_size)]
    lib.mapd_planes_get.restype = None
    lib.mapd_planes_boundary.argtypes = [ctypes.c_void_p, c_size, ctypes.POINTER(c_double)]
    lib.mapd_planes_boundary.restype = None
    lib.mapd_planes_inliers.argtypes = [ctypes.c_void_p, c_size, ctypes.POINTER(ctypes.c_int32)]
    lib.mapd_planes_inliers.restype = None
    lib.mapd_planes_free.argtypes = [ctypes.c_void_p]
    lib.mapd_planes_free.restype = None
    lib.mapd_read_cloud.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_void_p),
                                    ctypes.c_char_p, c_size]
    lib.mapd_read_cloud.restype = c_int
    lib.mapd_cloud_size.argtypes = [ctypes.c_void_p]
    lib.mapd_cloud_size.restype = c_size
    lib.mapd_cloud_shape.argtypes = [ctypes.c_void_p, ctypes.POINTER(c_int),
                                     ctypes.POINTER(c_int)]
    lib.mapd_cloud_shape.restype = None
    lib.mapd_cloud_points.argtypes = [ctypes.c_void_p]
    lib.mapd_cloud_points.restype = ctypes.POINTER(ctypes.c_float)
    lib.mapd_cloud_free.argtypes = [ctypes.c_void_p]
    lib.mapd_cloud_free.restype = None
    _lib = lib
    return lib


@dataclass
class PlaneExtractionParams:
    """robot::PlaneExtractionParams; None takes the C++ default (checked there)."""
    segmentation: str = "ransac"            # or "region_growing"
    distance_m: Optional[float] = None
    max_iterations: Optional[int] = None
    min_inliers: Optional[int] = None
    min_extent_m: Optional[float] = None
    min_width_m: Optional[float] = None
    min_rows: Optional[int] = None
    max_rms_m: Optional[float] = None
    max_planes: Optional[int] = None
    jump_base_m: Optional[float] = None
    jump_factor: Optional[float] = None
    normal_neighbours: Optional[int] = None
    smoothness_deg: Optional[float] = None
    max_curvature: Optional[float] = None

    def _to_c(self) -> _Params:
        c = _Params()
        _library().mapd_plane_params_default(ctypes.byref(c))
        if self.segmentation not in ("ransac", "region_growing"):
            raise ValueError(f"segmentation is {self.segmentation!r}, allowed: 'ransac', "
                             "'region_growing'")
        c.segmentation = 1 if self.segmentation == "region_growing" else 0
        for name, _ in _Params._fields_[1:]:
            value = getattr(self, name)
            if value is not None:
                if name == "min_inliers" and value < 0:
                    raise ValueError(f"plane extraction params: min_inliers is {value}, "
                                     "allowed: >= 3")
                setattr(c, name, value)
        return c


@dataclass
class ExtractedPlane:
    normal: Tuple[float, float, float]      # unit, sensor frame, towards the sensor
    offset_m: float                          # normal . p + offset_m = 0 on the plane
    boundary: List[Tuple[float, float, float]]  # convex hull of its inliers, sensor frame
    inliers: List[int] = field(default_factory=list)  # indices into the points given
    rms_m: float = 0.0                       # of the least-squares refit


@dataclass
class Cloud:
    points: "array"   # x y z floats, flat (3 per point)
    rows: int = 0     # organised: rows x columns; unorganised: 0 x 0
    columns: int = 0

    def __len__(self) -> int:
        return len(self.points) // 3


def _flat_floats(points) -> Tuple[object, int]:
    """The points as contiguous float32 x y z and their count (a numpy array is
    used as it is when it already is float32 and C-contiguous)."""
    if isinstance(points, array) and points.typecode == "f":
        if len(points) % 3:
            raise ValueError(f"points has {len(points)} floats: not x y z triples")
        return points, len(points) // 3
    shape = getattr(points, "shape", None)
    if shape is not None:  # numpy, without importing it
        if len(shape) != 2 or shape[1] != 3:
            raise ValueError(f"points has shape {tuple(shape)}, expected (N, 3)")
        flat = points.astype("float32", order="C", copy=False).reshape(-1)
        return flat, int(shape[0])
    flat = array("f")
    for i, p in enumerate(points):
        if len(p) != 3:
            raise ValueError(f"points[{i}] has {len(p)} values, expected x, y, z")
        flat.extend(p)
    return flat, len(flat) // 3


def _address(flat) -> int:
    if isinstance(flat, array):
        return flat.buffer_info()[0] if len(flat) else 0
    return flat.ctypes.data  # numpy


def extract_planes(points, rows: int = 0, columns: int = 0, wrap_columns: bool = False,
                   params: Optional[PlaneExtractionParams] = None) -> List[ExtractedPlane]:
    """robot::ExtractPlanes: the planes of one scan. Organised (a LiDAR's or a
    depth camera's image, row-major) when rows and columns are given, with
    wrap_columns for a 360 degree LiDAR; unorganised when they are 0."""
    lib = _library()
    flat, count = _flat_floats(points)
    c_params = (params or PlaneExtractionParams())._to_c()
    handle = ctypes.c_void_p()
    error = ctypes.create_string_buffer(1024)
    rc = lib.mapd_extract_planes(_address(flat), count, rows, columns, int(wrap_columns),
                                 ctypes.byref(c_params), ctypes.byref(handle), error,
                                 len(error))
    if rc != 0:
        raise ValueError(error.value.decode(errors="replace"))
    try:
        out = []
        normal = (ctypes.c_double * 3)()
        offset, rms = ctypes.c_double(), ctypes.c_double()
        nb, ni = ctypes.c_size_t(), ctypes.c_size_t()
        for i in range(lib.mapd_planes_count(handle)):
            lib.mapd_planes_get(handle, i, normal, ctypes.byref(offset), ctypes.byref(rms),
                                ctypes.byref(nb), ctypes.byref(ni))
            boundary = (ctypes.c_double * (3 * nb.value))()
            lib.mapd_planes_boundary(handle, i, boundary)
            inliers = (ctypes.c_int32 * ni.value)()
            lib.mapd_planes_inliers(handle, i, inliers)
            out.append(ExtractedPlane(
                normal=tuple(normal), offset_m=offset.value,
                boundary=[tuple(boundary[3 * k:3 * k + 3]) for k in range(nb.value)],
                inliers=list(inliers), rms_m=rms.value))
        return out
    finally:
        lib.mapd_planes_free(handle)


def read_cloud(path: str) -> Cloud:
    """robot::ReadCloudFile: a .pcd, .ply, KITTI .bin or x y z text file.
    FileNotFoundError when it cannot be opened, ValueError when it is not a cloud."""
    lib = _library()
    handle = ctypes.c_void_p()
    error = ctypes.create_string_buffer(1024)
    rc = lib.mapd_read_cloud(os.fsencode(path), ctypes.byref(handle), error, len(error))
    if rc != 0:
        message = error.value.decode(errors="replace")
        raise FileNotFoundError(message) if rc == 2 else ValueError(message)
    try:
        n = lib.mapd_cloud_size(handle)
        rows, columns = ctypes.c_int(), ctypes.c_int()
        lib.mapd_cloud_shape(handle, ctypes.byref(rows), ctypes.byref(columns))
        points = array("f")
        if n:
            points.frombytes(ctypes.string_at(lib.mapd_cloud_points(handle), 12 * n))
        return Cloud(points=points, rows=rows.value, columns=columns.value)
    finally:
        lib.mapd_cloud_free(handle)


def plane_batch(robot_id: str, session_id: str, seq: int, stamp_ns: int,
                translation: Sequence[float], rotation_wxyz: Sequence[float],
                planes: Sequence[ExtractedPlane],
                frame: int = pb.SESSION_FRAME_MAP) -> "pb.ObservationBatch":
    """robot::FeatureBatch with planes only: one scan's planes (sensor frame)
    seen from the sensor pose (metres; unit quaternion w, x, y, z) in the
    session frame. ValueError naming what the server would refuse."""
    from mapd_client.laser import line_batch  # the header and pose checks
    batch = line_batch(robot_id, session_id, seq, stamp_ns, translation, rotation_wxyz, [],
                       frame)
    for i, plane in enumerate(planes):
        n = plane.normal
        if not all(math.isfinite(v) for v in n) or abs(math.sqrt(sum(v * v for v in n)) - 1) > 1e-3:
            raise ValueError(f"planes[{i}].normal is not a unit vector")
        if not math.isfinite(plane.offset_m):
            raise ValueError(f"planes[{i}].offset is not finite")
        if len(plane.boundary) < 3 or not all(math.isfinite(v) for p in plane.boundary for v in p):
            raise ValueError(f"planes[{i}].boundary needs 3 or more finite points")
        out = batch.planes.add()
        out.normal.x, out.normal.y, out.normal.z = n
        out.offset = plane.offset_m
        for p in plane.boundary:
            q = out.boundary.add()
            q.x, q.y, q.z = p
    return batch


__all__ = ["PlaneExtractionParams", "ExtractedPlane", "Cloud", "extract_planes", "read_cloud",
           "plane_batch"]
