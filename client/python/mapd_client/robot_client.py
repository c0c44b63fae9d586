"""RobotClient: how a robot streams observation batches to mapd, in Python.

The same guarantees as the C++ client (client/robot_client.h):

- send() queues a batch on the one Ingest stream and returns without waiting
  for its acknowledgement (pipelining); the client keeps every batch until the
  server's IngestAck for it arrives.
- When the stream fails the client reconnects (with backoff) and resends, in
  the original order, every batch not yet acknowledged. Resending is safe: the
  server answers a batch it already stored with DUPLICATE and applies nothing
  twice, and DUPLICATE counts as acknowledged.
- REJECTED with UNAVAILABLE (the server draining) is no verdict: the batch is
  kept and resent on the next stream. Other rejections are final and listed
  in rejections().
- UNAUTHENTICATED or PERMISSION_DENIED ends the client at once (retrying
  cannot help); other failures are retried until give_up_after_s passes with
  no ack.

Acks are matched to batches by (session_id, seq), which must be unique among
the batches in flight. send(), wait_for_acks(), finish() and the accessors may
be called from any thread; one reader thread collects the acks and owns
reconnection.
"""

import dataclasses
import queue
import threading
import time
from typing import Dict, List, Optional, Tuple

import grpc

from mapd_client._proto import pb, pb_grpc

_END = object()  # ends a stream's request iterator: the half-close


@dataclasses.dataclass
class IngestCounts:
    sent: int = 0        # distinct batches passed to send()
    stored: int = 0      # acknowledged STORED
    duplicate: int = 0   # acknowledged DUPLICATE (stored before, e.g. resent after a drop)
    rejected: int = 0    # acknowledged REJECTED (final: the batch is wrong)
    reconnects: int = 0  # streams opened after the first one


@dataclasses.dataclass
class Rejection:
    session_id: str
    seq: int
    code: grpc.StatusCode
    message: str  # names the offending field, e.g. "lines[3].a.x is NaN"


class IngestError(Exception):
    """finish() could not get every batch acknowledged."""

    def __init__(self, code: grpc.StatusCode, message: str):
        super().__init__(f"{message} ({code.name})")
        self.code = code
        self.message = message


_CODES = {c.value[0]: c for c in grpc.StatusCode}


class RobotClient:
    """One Ingest stream with resend-on-reconnect. Use as a context manager or
    call finish() (then close())."""

    def __init__(self, channel: grpc.Channel, token: str = "",
                 give_up_after_s: float = 30.0, initial_backoff_s: float = 0.1,
                 max_backoff_s: float = 2.0, max_unacknowledged: int = 1000,
                 map_id: str = ""):
        """map_id: the map the batches are for when mapd serves several;
        "" = the server's default map. Another map than "default" is first
        looked up with ListMaps: a server that knows no maps (a mapd from
        before them would store the batches in its only map) or not this one
        makes finish() raise IngestError FAILED_PRECONDITION / NOT_FOUND, with
        nothing sent."""
        self._channel = channel
        self._stub = pb_grpc.MapServiceStub(channel)
        self._metadata = [("authorization", "Bearer " + token)] if token else []
        self._map_id = map_id
        if map_id:
            self._metadata.append(("mapd-map-id", map_id))
        self._give_up_after_s = give_up_after_s
        self._initial_backoff_s = initial_backoff_s
        self._max_backoff_s = max_backoff_s
        self._max_unacknowledged = max_unacknowledged

        # Lock order: _write_mu before _mu.
        self._write_mu = threading.Lock()  # queueing vs. replacing the stream
        self._requests: Optional[queue.Queue] = None  # the stream's requests; None between streams
        self._half_closed = False
        self._mu = threading.Lock()
        self._cv = threading.Condition(self._mu)
        self._pending: Dict[int, pb.ObservationBatch] = {}  # by order of first send(); dicts keep it
        self._order_of: Dict[Tuple[str, int], int] = {}
        self._next_order = 0
        self._counts = IngestCounts()
        self._rejections: List[Rejection] = []
        self._closing = False
        self._stopping = False
        self._gave_up = False
        self._reader_done = False
        self._last_error: Tuple[grpc.StatusCode, str] = (grpc.StatusCode.OK, "")
        self._call = None  # the current stream, for cancelling

        self._reader = threading.Thread(target=self._reader_loop, name="mapd-robot-client",
                                        daemon=True)
        self._reader.start()

    # -- public

    def send(self, batch: pb.ObservationBatch) -> None:
        """Queues `batch` and keeps it until it is acknowledged; does not wait
        for the ack. Blocks while max_unacknowledged batches are in flight."""
        with self._cv:
            self._cv.wait_for(lambda: len(self._pending) < self._max_unacknowledged
                              or self._gave_up or self._stopping or self._reader_done)
        # _write_mu is held from queueing to writing so that a reconnect (which
        # resends everything pending) cannot interleave and send it twice.
        with self._write_mu:
            copy = pb.ObservationBatch()
            copy.CopyFrom(batch)
            with self._mu:
                key = (copy.session_id, copy.seq)
                old = self._order_of.get(key)
                if old is not None:
                    self._pending.pop(old, None)  # sent again before its ack
                order = self._next_order
                self._next_order += 1
                self._order_of[key] = order
                self._pending[order] = copy
                self._counts.sent += 1
                if self._gave_up or self._stopping:
                    return
            # Between streams the reader sends it on reconnecting.
            if self._requests is not None and not self._half_closed:
                self._requests.put(copy)

    def wait_for_acks(self, timeout_s: float) -> bool:
        """True once every batch sent so far has a final ack; False after
        timeout_s or when the client gave up."""
        with self._cv:
            self._cv.wait_for(lambda: not self._pending or self._gave_up or self._reader_done,
                              timeout=timeout_s)
            return not self._pending

    def finish(self, timeout_s: float = 30.0) -> None:
        """Waits for the acks, half-closes the stream and stops the reader.
        Raises IngestError when batches stay unacknowledged."""
        deadline = time.monotonic() + timeout_s
        if self.wait_for_acks(timeout_s):
            with self._mu:
                self._closing = True
            with self._write_mu:
                if self._requests is not None and not self._half_closed:
                    self._requests.put(_END)
                    self._half_closed = True
        with self._cv:
            self._cv.wait_for(lambda: self._reader_done,
                              timeout=max(0.0, deadline - time.monotonic()) + 1.0)
            if not self._reader_done:
                self._cancel_locked()
        self._reader.join()
        with self._mu:
            if not self._pending:
                return
            if self._gave_up:
                raise IngestError(*self._last_error)
            raise IngestError(grpc.StatusCode.DEADLINE_EXCEEDED,
                              f"{len(self._pending)} batches still unacknowledged after "
                              f"{timeout_s:.1f} s")

    def close(self) -> None:
        """Stops at once: cancels the stream (unacknowledged batches stay so)."""
        with self._mu:
            self._cancel_locked()
        self._reader.join()

    def __enter__(self) -> "RobotClient":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.finish()
        else:
            self.close()

    def counts(self) -> IngestCounts:
        with self._mu:
            return dataclasses.replace(self._counts)

    def rejections(self) -> List[Rejection]:
        with self._mu:
            return list(self._rejections)

    def unacknowledged(self) -> int:
        with self._mu:
            return len(self._pending)

    # -- the reader thread

    def _cancel_locked(self) -> None:
        self._stopping = True
        if self._call is not None:
            self._call.cancel()
        self._cv.notify_all()

    def _open_stream(self):
        """A new stream, fed with every pending batch first."""
        with self._write_mu:
            requests: queue.Queue = queue.Queue()
            with self._mu:
                for batch in self._pending.values():
                    requests.put(batch)
                closing = self._closing
            self._half_closed = closing
            if closing:
                requests.put(_END)

            def request_iterator():
                while True:
                    item = requests.get()
                    if item is _END:
                        return
                    yield item

            call = self._stub.Ingest(request_iterator(), metadata=self._metadata)
            self._requests = requests
            with self._mu:
                self._call = call
                if self._stopping:
                    call.cancel()
            return call, requests

    def _close_stream(self, requests: queue.Queue) -> None:
        with self._write_mu:
            requests.put(_END)  # ends the request iterator's thread
            self._requests = None
        with self._mu:
            self._call = None

    def _check_map(self) -> Tuple[grpc.StatusCode, str]:
        """OK when the server serves self._map_id, else why not."""
        try:
            maps = self._stub.ListMaps(pb.ListMapsRequest(), timeout=10.0,
                                       metadata=self._metadata)
        except grpc.RpcError as error:
            if error.code() == grpc.StatusCode.UNIMPLEMENTED:
                return (grpc.StatusCode.FAILED_PRECONDITION,
                        f"map '{self._map_id}': the server serves one map and knows no others "
                        "(a mapd from before maps); nothing was sent: upgrade it, or send "
                        "without a map")
            return error.code(), error.details() or ""
        if any(m.map_id == self._map_id for m in maps.maps):
            return grpc.StatusCode.OK, ""
        return (grpc.StatusCode.NOT_FOUND,
                f"the server does not serve map '{self._map_id}' (ListMaps; an admin makes "
                "one with mapctl maps create)")

    def _reader_loop(self) -> None:
        failing_since: Optional[float] = None
        backoff = self._initial_backoff_s
        first = True
        map_checked = self._map_id in ("", "default")  # every server serves that one
        while True:
            with self._mu:
                if self._stopping or (self._closing and not self._pending):
                    break
                if not first:
                    self._counts.reconnects += 1
            first = False
            got_ack = False
            code, message = grpc.StatusCode.OK, ""
            if not map_checked:
                code, message = self._check_map()
                map_checked = code == grpc.StatusCode.OK
            if map_checked:
                call, requests = self._open_stream()
                try:
                    for ack in call:
                        self._handle_ack(ack)
                        got_ack = True
                except grpc.RpcError as error:
                    code, message = error.code(), error.details() or ""
                self._close_stream(requests)

            with self._cv:
                if self._stopping or (self._closing and not self._pending):
                    break
                now = time.monotonic()
                if got_ack or failing_since is None:
                    failing_since = now
                    if got_ack:
                        backoff = self._initial_backoff_s
                if code == grpc.StatusCode.OK:
                    code, message = (grpc.StatusCode.UNAVAILABLE,
                                     f"the server ended the Ingest stream with "
                                     f"{len(self._pending)} batches unacknowledged")
                self._last_error = (code, message)
                give_up_at = failing_since + self._give_up_after_s
                # Final: retrying cannot help (credentials, or a map the server lacks).
                refused = code in (grpc.StatusCode.UNAUTHENTICATED,
                                   grpc.StatusCode.PERMISSION_DENIED,
                                   grpc.StatusCode.FAILED_PRECONDITION,
                                   grpc.StatusCode.NOT_FOUND)
                if now >= give_up_at or refused:
                    self._gave_up = True
                    break
                self._cv.wait_for(lambda: self._stopping, timeout=backoff)
                backoff = min(backoff * 2, self._max_backoff_s)
            self._wait_for_channel(give_up_at)
        with self._cv:
            self._reader_done = True
            self._cv.notify_all()

    def _wait_for_channel(self, deadline: float) -> None:
        # One future (it asks the channel to connect), waited on in slices so
        # that close() is noticed; cancelled after, so no subscription is left.
        ready = grpc.channel_ready_future(self._channel)
        try:
            while time.monotonic() < deadline:
                with self._mu:
                    if self._stopping:
                        return
                try:
                    ready.result(timeout=min(0.2, max(0.0, deadline - time.monotonic())))
                    return
                except grpc.FutureTimeoutError:
                    continue
        finally:
            ready.cancel()

    def _handle_ack(self, ack: pb.IngestAck) -> None:
        with self._cv:
            order = self._order_of.get((ack.session_id, ack.seq))
            if order is None:
                return  # not pending (e.g. a resend's second answer)
            if ack.result == pb.IngestAck.STORED:
                self._counts.stored += 1
            elif ack.result == pb.IngestAck.DUPLICATE:
                self._counts.duplicate += 1
            elif ack.result == pb.IngestAck.REJECTED:
                code = _CODES.get(ack.code, grpc.StatusCode.UNKNOWN)
                if code == grpc.StatusCode.UNAVAILABLE:
                    return  # draining: kept, resent on the next stream
                self._counts.rejected += 1
                self._rejections.append(Rejection(ack.session_id, ack.seq, code, ack.message))
            else:
                return  # RESULT_UNSPECIFIED: not final
            del self._pending[order]
            del self._order_of[(ack.session_id, ack.seq)]
            self._cv.notify_all()
