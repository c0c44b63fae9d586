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

Several mapd on one database (docs/scale-out.md): given the other instances'
addresses (or a connect function), the client follows a redirect to the
map's owner (trailing metadata mapd-map-owner), waits as asked while the map
is being taken over (mapd-retry-after-ms), and moves to the next address
when the server cannot be reached, so a robot finds its map's new owner
within a lease or so of the old one dying.

Acks are matched to batches by (session_id, seq), which must be unique among
the batches in flight. send(), wait_for_acks(), finish() and the accessors may
be called from any thread; one reader thread collects the acks and owns
reconnection.
"""

import dataclasses
import queue
import threading
import time
from typing import Callable, Dict, List, Optional, Sequence, Tuple

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
    redirects: int = 0   # moves to another instance (a redirect, or the next address)


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

# A robot's channel: a dead host is noticed in seconds by keepalive pings
# (mapd permits one every 5 s), and a restarted one is found again quickly.
ROBOT_CHANNEL_OPTIONS = [
    ("grpc.initial_reconnect_backoff_ms", 200), ("grpc.min_reconnect_backoff_ms", 200),
    ("grpc.max_reconnect_backoff_ms", 2000), ("grpc.keepalive_time_ms", 5000),
    ("grpc.keepalive_timeout_ms", 3000), ("grpc.keepalive_permit_without_calls", 0),
    ("grpc.http2.max_pings_without_data", 0),
]


def robot_channel(address: str,
                  credentials: Optional[grpc.ChannelCredentials] = None) -> grpc.Channel:
    """A channel with ROBOT_CHANNEL_OPTIONS: plain, or TLS with `credentials`."""
    if credentials is None:
        return grpc.insecure_channel(address, options=ROBOT_CHANNEL_OPTIONS)
    return grpc.secure_channel(address, credentials, options=ROBOT_CHANNEL_OPTIONS)


def _trailing(error: grpc.RpcError, key: str) -> str:
    try:
        metadata = error.trailing_metadata() or ()
    except AttributeError:
        return ""
    for k, v in metadata:
        if k == key:
            return v.decode() if isinstance(v, bytes) else v
    return ""


class RobotClient:
    """One Ingest stream with resend-on-reconnect. Use as a context manager or
    call finish() (then close())."""

    def __init__(self, channel: grpc.Channel, token: str = "",
                 give_up_after_s: float = 30.0, initial_backoff_s: float = 0.1,
                 max_backoff_s: float = 2.0, max_unacknowledged: int = 1000,
                 map_id: str = "", addresses: Sequence[str] = (),
                 connect: Optional[Callable[[str], grpc.Channel]] = None):
        """map_id: the map the batches are for when mapd serves several;
        "" = the server's default map. Another map than "default" is first
        looked up with ListMaps: a server that knows no maps (a mapd from
        before them would store the batches in its only map) or not this one
        makes finish() raise IngestError FAILED_PRECONDITION / NOT_FOUND, with
        nothing sent.

        addresses: the other mapd instances ("host:port") sharing the map's
        database; connect(address) makes a channel to one (default:
        robot_channel, plain; pass one with TLS credentials off loopback).
        With either, redirects are followed and the addresses tried in turn
        when the server cannot be reached."""
        self._first_channel = channel
        self._channel = channel
        self._stub = pb_grpc.MapServiceStub(channel)
        self._addresses = list(addresses)
        self._connect = connect or (robot_channel if self._addresses else None)
        self._next_address = 0
        self._owned_channel: Optional[grpc.Channel] = None  # one this client made
        self._metadata = [("authorization", "Bearer " + token)] if token else []
        self._map_id = map_id
        if map_id:
            self._metadata.append(("mapd-map-id", map_id))
        if self._connect is not None:  # redirected to the owner, not relayed by another mapd
            self._metadata.append(("mapd-follows-redirects", "1"))
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
        self._close_owned_channel()
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
        self._close_owned_channel()

    def _close_owned_channel(self) -> None:
        with self._write_mu:
            owned, self._owned_channel = self._owned_channel, None
        if owned is not None:
            owned.close()

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
            redirect = ""  # the map's owner, when this mapd does not serve it
            retry_after_s: Optional[float] = None  # set while the map is being taken over
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
                    redirect = _trailing(error, "mapd-map-owner")
                    retry_after = _trailing(error, "mapd-retry-after-ms")
                    if retry_after.isdigit():
                        retry_after_s = int(retry_after) / 1000.0
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
                # A redirect is followed after the shortest pause: the owner is
                # known. A takeover in progress is asked about again as often
                # as it may end.
                if redirect and self._connect is not None:
                    backoff = self._initial_backoff_s
                pause = (backoff if retry_after_s is None
                         else max(self._initial_backoff_s, retry_after_s))
                self._cv.wait_for(lambda: self._stopping, timeout=pause)
                if retry_after_s is None:
                    backoff = min(backoff * 2, self._max_backoff_s)
            if self._move_after_failure(code, redirect, give_up_at):
                # Failing over: the new owner takes the map within a few
                # seconds; find it within a fraction of one, not after a
                # backoff grown on the instances that were not it yet.
                backoff = min(backoff, 4 * self._initial_backoff_s)
                with self._mu:
                    self._counts.redirects += 1
        with self._cv:
            self._reader_done = True
            self._cv.notify_all()

    def _move_after_failure(self, code: grpc.StatusCode, redirect: str,
                            give_up_at: float) -> bool:
        """After a failed stream: to the owner named by a redirect, or to the
        next address when this server cannot be reached; True if moved."""
        if self._connect is None:
            self._wait_for_channel(give_up_at)
            return False
        if redirect:
            self._switch_to(self._connect(redirect))
            return True
        if not self._addresses or code != grpc.StatusCode.UNAVAILABLE:
            self._wait_for_channel(give_up_at)
            return False
        # Unreachable, or its map is being taken over: give this server a
        # little while (a restart, or the takeover finishing), then try the
        # next. A refused connection (the process is gone) moves on at once.
        deadline = min(give_up_at, time.monotonic() + self._max_backoff_s)
        if self._wait_ready_or_failing(deadline) == grpc.ChannelConnectivity.READY:
            return False
        n = len(self._addresses)
        i = self._next_address % (n + 1)
        self._next_address += 1
        self._switch_to(self._connect(self._addresses[i]) if i < n else self._first_channel)
        return True

    def _switch_to(self, channel: grpc.Channel) -> None:
        with self._write_mu:
            old = self._owned_channel
            self._channel = channel
            self._stub = pb_grpc.MapServiceStub(channel)
            self._owned_channel = channel if channel is not self._first_channel else None
        if old is not None and old is not channel:
            old.close()

    def _wait_ready_or_failing(self, deadline: float) -> grpc.ChannelConnectivity:
        """The channel's state once READY or TRANSIENT_FAILURE, or at deadline."""
        states: "queue.Queue[grpc.ChannelConnectivity]" = queue.Queue()
        self._channel.subscribe(states.put, try_to_connect=True)
        state = grpc.ChannelConnectivity.IDLE
        try:
            while time.monotonic() < deadline:
                with self._mu:
                    if self._stopping:
                        break
                try:
                    state = states.get(timeout=min(0.2, max(0.0, deadline - time.monotonic())))
                except queue.Empty:
                    continue
                if state in (grpc.ChannelConnectivity.READY,
                             grpc.ChannelConnectivity.TRANSIENT_FAILURE):
                    break
        finally:
            self._channel.unsubscribe(states.put)
        return state

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
