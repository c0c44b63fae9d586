"""MapClient: the read and operator side of the API, one call per method.

Every method returns the protobuf messages of mapserver.v1 (mapd_client.pb)
or plain lists of them, and raises grpc.RpcError with the server's status
(INVALID_ARGUMENT naming the field, FAILED_PRECONDITION for a refused merge,
NOT_FOUND, PERMISSION_DENIED ...) as any gRPC call does.
"""

import os
from typing import Callable, Iterator, List, NamedTuple, Optional, Sequence, Tuple

import grpc

from mapd_client._proto import pb, pb_grpc
from mapd_client.watch import FeatureWatch, watch_request

CHUNK_BYTES = 1 << 20  # the API's largest chunk


class FeatureMap(NamedTuple):
    features: List[pb.FusedFeature]  # fused walls, map frame
    planes: List[pb.FusedPlane]      # fused floors, ceilings, ramps
    map_version: int                 # observations the map reflects
    fusion_pending: int              # acknowledged observations not reflected yet


def connect(address: str = "127.0.0.1:50051", root_certificates: Optional[bytes] = None,
            private_key: Optional[bytes] = None,
            certificate_chain: Optional[bytes] = None) -> grpc.Channel:
    """A channel to mapd: plain on loopback, TLS when a CA is given (and mTLS
    with a client key and certificate). Reconnects quickly after a restart."""
    options = [("grpc.initial_reconnect_backoff_ms", 200), ("grpc.max_reconnect_backoff_ms", 2000)]
    if root_certificates is None:
        return grpc.insecure_channel(address, options=options)
    credentials = grpc.ssl_channel_credentials(root_certificates, private_key, certificate_chain)
    return grpc.secure_channel(address, credentials, options=options)


class MapNotServed(Exception):
    """The server does not serve the MapClient's map_id: it knows no maps (a
    mapd from before them would answer for its only map) or not this one."""


class MapClient:
    def __init__(self, channel: grpc.Channel, token: str = "", timeout_s: float = 30.0,
                 map_id: str = "", connect: Optional[Callable[[str], grpc.Channel]] = None):
        """map_id: the map every call is about, when mapd serves several; "" =
        the server's default map. Another map than "default" is looked up
        with ListMaps before the first call, which raises MapNotServed if the
        server knows no maps or not this one.

        connect(address) -> channel: with several mapd on one database, the
        first call about the map asks LocateMap which instance serves it and
        goes there through connect (e.g. mapd_client.connect). Without it,
        a call to an instance that does not serve the map fails UNAVAILABLE
        naming the owner. After a failover, a new MapClient finds the new
        owner."""
        self._stub = pb_grpc.MapServiceStub(channel)
        self._connect = connect
        self._owner_channel: Optional[grpc.Channel] = None
        self._metadata = [("authorization", "Bearer " + token)] if token else []
        self._timeout_s = timeout_s
        self._map_id = map_id
        self._map_checked = map_id in ("", "default")

    def _map_stub(self) -> pb_grpc.MapServiceStub:
        """The stub for calls about the map, once the map is known served (and,
        with connect, located): called before the call's arguments are."""
        if not self._map_checked:
            try:
                served = [m.map_id for m in self.maps().maps]
            except grpc.RpcError as error:
                if error.code() != grpc.StatusCode.UNIMPLEMENTED:
                    raise
                raise MapNotServed(f"map '{self._map_id}': the server serves one map and knows "
                                   "no others (a mapd from before maps); upgrade it, or leave "
                                   "map_id empty") from None
            if self._map_id not in served:
                raise MapNotServed(f"the server does not serve map '{self._map_id}'; it serves: "
                                   + ", ".join(served))
            self._map_checked = True
        if self._connect is not None and self._owner_channel is None:
            self._go_to_owner()
        return self._stub

    def _md(self) -> List[Tuple[str, str]]:
        """The metadata of a call about the map."""
        if not self._map_id:
            return self._metadata
        return self._metadata + [("mapd-map-id", self._map_id)]

    def _go_to_owner(self) -> None:
        """Moves this client's map calls to the instance serving the map."""
        try:
            where = self.locate()
        except grpc.RpcError as error:
            if error.code() == grpc.StatusCode.UNIMPLEMENTED:
                return  # a mapd from before LocateMap serves its maps itself
            raise
        if where.here or not where.live or not where.address:
            return  # here, or nobody yet: the call's own error says so
        self._owner_channel = self._connect(where.address)
        self._stub = pb_grpc.MapServiceStub(self._owner_channel)

    def locate(self) -> pb.MapLocation:
        """Which mapd instance serves this client's map (LocateMap)."""
        return self._stub.LocateMap(pb.LocateMapRequest(map_id=self._map_id),
                                    timeout=self._timeout_s, metadata=self._metadata)

    # -- maps

    def maps(self, archived: bool = False) -> pb.ListMapsResponse:
        """The maps the server serves (ListMaps); archived=True: the archived
        ones instead (delete_map), with archived_ns."""
        return self._stub.ListMaps(pb.ListMapsRequest(archived=archived),
                                   timeout=self._timeout_s, metadata=self._metadata)

    def create_map(self, map_id: str, settings: Optional[dict] = None) -> pb.MapInfo:
        """A new, empty map (role admin; mapd --data-dir). settings: its own
        fusion.*, planes.* and merge.* settings over mapd's, e.g.
        {"fusion.eta_m": "0.2"}."""
        request = pb.CreateMapRequest(map_id=map_id, settings=settings or {})
        return self._stub.CreateMap(request, timeout=self._timeout_s, metadata=self._metadata)

    def delete_map(self, map_id: str, purge: bool = False) -> pb.DeleteMapResponse:
        """Stops serving a map (role admin) and archives it, or with
        purge=True deletes its data for good. Not the default map."""
        request = pb.DeleteMapRequest(map_id=map_id, purge=purge)
        return self._stub.DeleteMap(request, timeout=self._timeout_s, metadata=self._metadata)

    def restore_map(self, map_id: str) -> pb.MapInfo:
        """Serves an archived map again, as it was (role admin)."""
        request = pb.RestoreMapRequest(map_id=map_id)
        return self._stub.RestoreMap(request, timeout=self._timeout_s, metadata=self._metadata)

    # -- the fused map

    def feature_map(self, bbox: Optional[Sequence[float]] = None, min_support: int = 0,
                    kind: int = pb.FEATURE_KIND_UNSPECIFIED, max_wait_ms: int = 0) -> FeatureMap:
        """Every page of GetFeatureMap in one FeatureMap. bbox: (xmin, ymin,
        xmax, ymax), map frame, metres."""
        request = pb.FeatureMapRequest(min_support=min_support, kind=kind, max_wait_ms=max_wait_ms)
        if bbox is not None:
            xmin, ymin, xmax, ymax = bbox
            request.bbox.min.x, request.bbox.min.y = xmin, ymin
            request.bbox.max.x, request.bbox.max.y = xmax, ymax
        features: List[pb.FusedFeature] = []
        planes: List[pb.FusedPlane] = []
        version = pending = 0
        for page in self._map_stub().GetFeatureMap(request, timeout=self._timeout_s,
                                                   metadata=self._md()):
            features.extend(page.features)
            planes.extend(page.planes)
            version, pending = page.map_version, page.fusion_pending
        return FeatureMap(features, planes, version, pending)

    def watch(self, bbox: Optional[Sequence[float]] = None, kind: Optional[int] = None,
              robot_id: Optional[str] = None, since_map_version: int = 0,
              reconnect: bool = True) -> FeatureWatch:
        """The WatchFeatureMap change feed: iterate it for FeatureMapDelta
        messages (LiveFeatureMap applies them); it reconnects from the last
        complete map_version when mapd restarts. close() or `with` ends it.
        A bad filter raises grpc.RpcError INVALID_ARGUMENT naming the field."""
        return FeatureWatch(self._map_stub(), self._md(), watch_request(bbox, kind, robot_id),
                            since_map_version=since_map_version, reconnect=reconnect)

    def stats(self) -> pb.Stats:
        return self._map_stub().GetStats(pb.GetStatsRequest(), timeout=self._timeout_s,
                                         metadata=self._md())

    def robots(self) -> List[pb.RobotInfo]:
        return list(self._map_stub().ListRobots(pb.ListRobotsRequest(), timeout=self._timeout_s,
                                                metadata=self._md()).robots)

    def trails(self, robot_id: str = "", max_poses_per_session: int = 0) -> List[pb.SessionTrail]:
        """Each robot session's sensor positions (map frame where frame_tied)."""
        request = pb.GetTrailsRequest(robot_id=robot_id,
                                      max_poses_per_session=max_poses_per_session)
        return list(self._map_stub().GetTrails(request, timeout=self._timeout_s,
                                               metadata=self._md()))

    # -- voxel submaps

    def upload_submap(self, path: str, robot_id: str, name: str = "", session_id: str = "",
                      resolution: float = 0.0) -> pb.SubmapInfo:
        """Uploads an OctoMap file (.bt or .ot, from the extension) in 1 MiB chunks."""
        extension = os.path.splitext(path)[1].lower()
        formats = {".bt": pb.SUBMAP_FORMAT_OCTOMAP_BT, ".ot": pb.SUBMAP_FORMAT_OCTOMAP_OT}
        if extension not in formats:
            raise ValueError(f"cannot tell the format of '{path}': want a .bt or .ot file")
        with open(path, "rb") as file:
            data = file.read()
        header = pb.SubmapHeader(robot_id=robot_id,
                                 name=name or os.path.splitext(os.path.basename(path))[0],
                                 format=formats[extension], resolution=resolution,
                                 session_id=session_id)
        return self.upload_submap_bytes(header, data)

    def upload_submap_bytes(self, header: pb.SubmapHeader, data: bytes) -> pb.SubmapInfo:
        def requests() -> Iterator[pb.UploadSubmapRequest]:
            yield pb.UploadSubmapRequest(header=header)
            for at in range(0, len(data), CHUNK_BYTES):
                yield pb.UploadSubmapRequest(chunk=data[at:at + CHUNK_BYTES])
        return self._map_stub().UploadSubmap(requests(), metadata=self._md())

    def list_submaps(self, robot_id: str = "") -> List[pb.SubmapInfo]:
        return list(self._map_stub().ListSubmaps(pb.ListSubmapsRequest(robot_id=robot_id),
                                                 timeout=self._timeout_s,
                                                 metadata=self._md()).submaps)

    def get_submap(self, submap_id: int) -> Tuple[pb.SubmapInfo, bytes]:
        """The stored file and its info."""
        return self._read_chunks(self._map_stub().GetSubmap(pb.GetSubmapRequest(id=submap_id),
                                                            metadata=self._md()))

    def global_map(self) -> Tuple[pb.SubmapInfo, bytes]:
        """The global map (OctoMap binary): the union of every submap placed in
        the map frame; NOT_FOUND while none is."""
        info, _, data = self.global_map_info()
        return info, data

    def global_map_info(self) -> Tuple[pb.SubmapInfo, pb.GlobalMapInfo, bytes]:
        """The global map with its version and members (submap ids and poses)."""
        info, about, parts = pb.SubmapInfo(), pb.GlobalMapInfo(), []
        for chunk in self._map_stub().GetGlobalMap(pb.GetGlobalMapRequest(), metadata=self._md()):
            if chunk.HasField("info"):
                info = chunk.info
            if chunk.HasField("global"):
                about = getattr(chunk, "global")
            parts.append(chunk.data)
        return info, about, b"".join(parts)

    def delete_submap(self, submap_id: int) -> None:
        self._map_stub().DeleteSubmap(pb.DeleteSubmapRequest(id=submap_id),
                                      timeout=self._timeout_s, metadata=self._md())

    def merge(self, submap_ids: Sequence[int],
              progress: Optional[Callable[[str, float], None]] = None,
              review: bool = False) -> pb.MergeResult:
        """Merges two or more submaps (the first is the reference frame).
        progress(stage, fraction) is called as the server reports. A merge with
        too little evidence raises grpc.RpcError FAILED_PRECONDITION with the
        figure that failed. review: only propose it (result.state
        MERGE_STATE_PROPOSED) until approve_merge()."""
        request = pb.MergeSubmapsRequest(submap_ids=submap_ids, review=review)
        result = None
        for message in self._map_stub().MergeSubmaps(request, metadata=self._md()):
            if progress is not None and message.stage:
                progress(message.stage, message.fraction)
            if message.HasField("result"):
                result = message.result
        if result is None:
            raise RuntimeError("the server ended the merge without a result")
        return result

    def list_merges(self, state: int = pb.MERGE_STATE_UNSPECIFIED) -> List[pb.MergeRecord]:
        return list(self._map_stub().ListMerges(pb.ListMergesRequest(state=state),
                                                timeout=self._timeout_s,
                                                metadata=self._md()).merges)

    def get_merge(self, merge_id: int) -> pb.MergeRecord:
        return self._map_stub().GetMerge(pb.GetMergeRequest(id=merge_id), timeout=self._timeout_s,
                                         metadata=self._md())

    def approve_merge(self, merge_id: int) -> pb.MergeRecord:
        return self._map_stub().ApproveMerge(pb.ApproveMergeRequest(id=merge_id),
                                             timeout=self._timeout_s, metadata=self._md())

    def reject_merge(self, merge_id: int, reason: str) -> pb.MergeRecord:
        return self._map_stub().RejectMerge(pb.RejectMergeRequest(id=merge_id, reason=reason),
                                            timeout=self._timeout_s, metadata=self._md())

    @staticmethod
    def _read_chunks(stream) -> Tuple[pb.SubmapInfo, bytes]:
        info = pb.SubmapInfo()
        parts = []
        for chunk in stream:
            if chunk.HasField("info"):
                info = chunk.info
            parts.append(chunk.data)
        return info, b"".join(parts)
