"""The WatchFeatureMap change feed: FeatureWatch (the deltas, reconnecting
like `mapctl watch`) and LiveFeatureMap (the filtered map they build).

    with MapClient(channel).watch(bbox=(0, 0, 10, 8)) as feed:
        live = LiveFeatureMap()
        for delta in feed:
            if live.apply(delta):   # complete: equals GetFeatureMap at live.map_version
                print(len(live.features))
"""

import threading
from typing import Dict, Iterator, List, Optional, Sequence

import grpc

from mapd_client._proto import pb

# An error a retry cannot cure; anything else (UNAVAILABLE on shutdown, a
# broken connection) is retried from the last complete version.
_PERMANENT = (grpc.StatusCode.INVALID_ARGUMENT, grpc.StatusCode.UNAUTHENTICATED,
              grpc.StatusCode.PERMISSION_DENIED, grpc.StatusCode.UNIMPLEMENTED,
              grpc.StatusCode.RESOURCE_EXHAUSTED, grpc.StatusCode.FAILED_PRECONDITION)


def watch_request(bbox: Optional[Sequence[float]] = None, kind: Optional[int] = None,
                  robot_id: Optional[str] = None) -> pb.WatchFeatureMapRequest:
    """bbox: (xmin, ymin, xmax, ymax), map frame, metres."""
    request = pb.WatchFeatureMapRequest(kind=kind or pb.FEATURE_KIND_UNSPECIFIED,
                                        robot_id=robot_id or "")
    if bbox is not None:
        xmin, ymin, xmax, ymax = bbox
        request.bbox.min.x, request.bbox.min.y = xmin, ymin
        request.bbox.max.x, request.bbox.max.y = xmax, ymax
    return request


class FeatureWatch:
    """Iterates the FeatureMapDelta messages of one watch, across reconnects.

    On a stream that ends for any reason but a permanent error (UNAVAILABLE
    when mapd shuts down, a broken connection) it waits (backoff 0.5 s
    doubling to 10 s, reset by any message), then for the server to be
    reachable again (however long mapd is down), and watches again from
    `resume_version`, the map_version of the last message with more = false
    (0 while a resync is incomplete: the client dropped its map for it). A
    permanent error (INVALID_ARGUMENT naming the field, PERMISSION_DENIED ...)
    is raised as grpc.RpcError, as is any error before the first message or
    with reconnect=False. close() (or leaving the `with`) cancels the call and
    ends the iteration without an error; it may be called from any thread.
    """

    def __init__(self, stub, metadata, request: pb.WatchFeatureMapRequest,
                 since_map_version: int = 0, reconnect: bool = True,
                 initial_backoff_s: float = 0.5, max_backoff_s: float = 10.0):
        self._stub = stub
        self._metadata = metadata
        self._request = request
        self._reconnect = reconnect
        self._initial_backoff_s = initial_backoff_s
        self._max_backoff_s = max_backoff_s
        self._closed = threading.Event()
        self._lock = threading.Lock()
        self._call = None
        self.resume_version = since_map_version
        self.reconnects = 0
        # The error the last reconnect was for ("CODE: details"; "" before any
        # or after a clean end): what to look at when a watch does not move.
        self.last_error = ""

    def close(self) -> None:
        self._closed.set()
        with self._lock:
            if self._call is not None:
                self._call.cancel()

    def __enter__(self) -> "FeatureWatch":
        return self

    def __exit__(self, *_exc) -> None:
        self.close()

    def __iter__(self) -> Iterator[pb.FeatureMapDelta]:
        received = False  # anything from this server yet
        backoff = self._initial_backoff_s
        while not self._closed.is_set():
            request = pb.WatchFeatureMapRequest()
            request.CopyFrom(self._request)
            request.since_map_version = self.resume_version
            with self._lock:
                if self._closed.is_set():
                    return
                # A reconnect waits for the server (wait_for_ready) rather than
                # failing at once while it is down: grpcio's iterator can block
                # for ever on a call that failed before reaching any server
                # (grpc/grpc#20562; seen with Debian's 1.51 across a restart).
                self._call = self._stub.WatchFeatureMap(request, metadata=self._metadata,
                                                        wait_for_ready=received or None)
            try:
                for delta in self._call:
                    received = True
                    backoff = self._initial_backoff_s
                    if delta.resync:
                        self.resume_version = 0  # until the resync is complete
                    if not delta.more:
                        self.resume_version = delta.map_version
                    yield delta
                error = None
            except grpc.RpcError as rpc_error:
                error = rpc_error
            finally:
                with self._lock:
                    self._call = None
            if self._closed.is_set():
                return
            code = error.code() if error is not None else grpc.StatusCode.OK
            if (code == grpc.StatusCode.INVALID_ARGUMENT and received and self.resume_version > 0
                    and "since_map_version" in (error.details() or "")):
                # A version this server does not know (its database was
                # replaced): start again from the full map.
                self.resume_version = 0
                continue
            if error is not None and (not self._reconnect or not received or code in _PERMANENT):
                raise error
            self.reconnects += 1
            self.last_error = f"{code.name}: {error.details()}" if error is not None else ""
            if self._closed.wait(backoff):
                return
            backoff = min(backoff * 2, self._max_backoff_s)


class LiveFeatureMap:
    """The filtered map a watch builds: features and planes by id.

    apply(delta) follows FeatureMapDelta's rules: a resync clears both maps;
    added and updated alike insert or replace by id; removed ids are erased
    (an unknown id is ignored). It returns True when the map is complete, i.e.
    equals the server's filtered map at `map_version` (the delta had
    more = false)."""

    def __init__(self):
        self.features: Dict[int, pb.FusedFeature] = {}
        self.planes: Dict[int, pb.FusedPlane] = {}
        self.map_version = 0  # of the last complete state
        self.complete = False

    def apply(self, delta: pb.FeatureMapDelta) -> bool:
        if delta.resync:
            self.features.clear()
            self.planes.clear()
        for feature in list(delta.added) + list(delta.updated):
            self.features[feature.id] = feature
        for feature_id in delta.removed:
            self.features.pop(feature_id, None)
        for plane in list(delta.added_planes) + list(delta.updated_planes):
            self.planes[plane.id] = plane
        for plane_id in delta.removed_planes:
            self.planes.pop(plane_id, None)
        self.complete = not delta.more
        if self.complete:
            self.map_version = delta.map_version
        return self.complete

    def feature_list(self) -> List[pb.FusedFeature]:
        return [self.features[k] for k in sorted(self.features)]

    def plane_list(self) -> List[pb.FusedPlane]:
        return [self.planes[k] for k in sorted(self.planes)]
