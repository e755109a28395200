"""The websocket fan-out of one event loop: every publication of the station's views is handed
over once (one ``call_soon_threadsafe``, whatever the number of clients), its messages are
framed once, and the same bytes are written to every client's socket in one pass, with no task
woken per client.

A client served by uvicorn's websockets protocol (the station's server) is written at its
transport directly (``DirectSocket``): the ASGI send path (a task per client, a coroutine chain
through Starlette and uvicorn, a frame built per client) cost ~40 us of the web thread per
client message, 14-17 % of a core for 25 clients at 60 Hz. A client whose socket still holds
unsent bytes is skipped (it gets the newest of each message once it has taken what it has: a
slow client skips worlds, it never queues them), and one whose peer has taken (acknowledged)
nothing for ``STALLED_CLIENT_S`` while it had bytes to take is dropped, its connection reset.
Any other server (a test client) is served through ASGI by its own loop
(``backend/routes/ws.py``), woken by the same hand-over.

Time (the world's turns, the stall timeout) is read from a ``Clock``: the loop's own by
default, a test's where the test drives the time."""

from __future__ import annotations

import asyncio
import contextlib
import socket
import struct
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from starlette.types import ASGIApp, Receive, Scope, Send
from websockets.frames import Frame, Opcode
from websockets.protocol import State

from .jsonsafe import dumps

if TYPE_CHECKING:
    from .station import Station
    from .viewhub import Views

try:  # Linux's count of the bytes of a TCP socket its peer has not acknowledged (SIOCOUTQ)
    import fcntl
    import termios
    _SIOCOUTQ: int | None = termios.TIOCOUTQ
except (ImportError, AttributeError):  # pragma: no cover - elsewhere: the user-space buffer only
    _SIOCOUTQ = None

try:  # the server's own websocket protocol (uvicorn's default with the websockets package)
    from uvicorn.protocols.websockets.websockets_sansio_impl import WebSocketsSansIOProtocol
except ImportError:  # pragma: no cover - another server: every client goes through ASGI
    WebSocketsSansIOProtocol = None  # type: ignore[assignment,misc]

#: a websocket client whose peer takes (acknowledges) none of the bytes written to it for this
#: long is dropped, its connection reset (it reconnects and gets a snapshot): it no longer
#: slows anyone, but it held its buffers for ever. Counted from the last byte its peer took:
#: a client that stops reading still takes ~300 kB into its receive buffer (0.2-0.3 s of the
#: full stream on loopback), so it goes within 2 s of its last read even on a loaded machine
#: (1.5 s gave 1.8-2.3 s at load 15)
STALLED_CLIENT_S = 1.25

#: how early (in periods of ``stream.ws_max_hz``) a world may go before its turn. The turns
#: stay a period apart on average, and a publication or a timer that came late (the station's
#: thread or this loop busy) does not make the next world wait: only a burst of more than this
#: many worlds above the rate does. With a quarter of a period a late world pushed the next
#: turn back, the next world waited on a timer, and a newer one replaced it before the timer
#: (late too) fired: 1-3 % of the worlds were lost so with 5 busy processes beside the
#: station, 13-14 % with publications and timers up to 0.9 period late (the tests' loop)
WORLD_BURST = 2.0


class Timer(Protocol):
    def cancel(self) -> None: ...


class Clock(Protocol):
    """The fan-out's time: ``now()`` (seconds, monotonic) and timers."""

    def now(self) -> float: ...

    def call_later(self, delay: float, callback: Callable[[], None]) -> Timer: ...


class LoopClock:
    """An event loop's monotonic clock and its timers."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self.loop = loop

    def now(self) -> float:
        return self.loop.time()

    def call_later(self, delay: float, callback: Callable[[], None]) -> Timer:
        return self.loop.call_later(delay, callback)


#: the scope key under which ``ServerSendTap`` keeps the server's own ``send`` of a websocket
SERVER_SEND = "touchline.server_send"


class ServerSendTap:
    """Keeps the ASGI server's own ``send`` of every websocket in its scope (``SERVER_SEND``),
    before any middleware wraps it, so the fan-out can reach the connection behind it. The
    outermost middleware; it changes nothing else."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "websocket":
            scope[SERVER_SEND] = send
        await self.app(scope, receive, send)


def params_message(st: Station) -> str:
    """The "params" message: the parameters' version and values."""
    params = st.params
    return dumps({"type": "params", "version": params.version, "values": params.values()},
                 "params")


def geometry_message(v: Views) -> str:
    """The "geometry" message of ``v``."""
    return dumps({"type": "geometry", "geometry": v.geometry}, "geometry")


def text_frame(text: str) -> bytes:
    """A server's websocket text frame (unmasked, unfragmented, no extension) of ``text``: the
    same bytes for every client."""
    return Frame(Opcode.TEXT, text.encode("utf-8")).serialize(mask=False)


class DirectSocket:
    """An accepted websocket of uvicorn's websockets protocol, written at its transport.

    Every write is whole frames, so they interleave with the protocol's own (pings, close)
    frame by frame; nothing is written once either side started closing."""

    def __init__(self, proto: Any) -> None:
        self.proto = proto
        self.transport: asyncio.WriteTransport = proto.transport
        sock = self.transport.get_extra_info("socket")
        self._fd: int | None = sock.fileno() if sock is not None else None
        self._outq = bytearray(4)

    def open(self) -> bool:
        p = self.proto
        return (not p.close_sent and not p.disconnected and p.conn.state is State.OPEN
                and not self.transport.is_closing())

    def buffered(self) -> int:
        """Bytes written that the socket has not taken yet."""
        return self.transport.get_write_buffer_size()

    def pending(self) -> int:
        """Bytes written that the peer has not taken: those still in ``buffered`` and those in
        the kernel's send queue that the peer has not acknowledged. The kernel's queue holds
        megabytes: a peer that stopped reading leaves nothing in ``buffered`` for seconds.
        Where the kernel does not tell (not Linux), ``buffered`` only."""
        if self._fd is not None and _SIOCOUTQ is not None:
            try:
                fcntl.ioctl(self._fd, _SIOCOUTQ, self._outq)
            except OSError:  # not a TCP socket (a Unix one): the user-space buffer only
                self._fd = None
            else:
                unacked: int = struct.unpack_from("i", self._outq)[0]
                return self.buffered() + unacked
        return self.buffered()

    def write(self, data: bytes) -> None:
        self.transport.write(data)

    def abort(self) -> None:
        """Resets the connection, dropping what it holds unsent (a close frame would wait
        behind it for ever, and the buffers with it). Lingering off first: a plain close of a
        socket whose peer reads nothing queues its FIN behind the megabytes the kernel holds
        for it, so the connection stayed in FIN-WAIT-1 with 2.3 MB of send queue and the peer
        saw nothing end; with a zero linger the kernel sends a reset and frees them."""
        sock = self.transport.get_extra_info("socket")
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        self.transport.abort()


def direct_socket(scope: Scope) -> DirectSocket | None:
    """The websocket of ``scope`` as a ``DirectSocket`` when the server is uvicorn's websockets
    protocol and the handshake is done (``ServerSendTap`` kept its send); else None (the
    client is served through ASGI)."""
    proto = getattr(scope.get(SERVER_SEND), "__self__", None)
    if (WebSocketsSansIOProtocol is None or not isinstance(proto, WebSocketsSansIOProtocol)
            or not getattr(proto, "handshake_complete", False)
            or getattr(proto, "transport", None) is None
            or not all(hasattr(proto, a) for a in ("close_sent", "disconnected", "conn"))):
        return None
    return DirectSocket(proto)


@dataclass(eq=False)
class DirectClient:
    """What one directly written client has been sent, and whether it is still served."""

    sock: DirectSocket
    world_key: tuple[object, ...]
    health_mono: float
    geometry_seq: int
    player_serial: int
    params_version: int
    #: set when the client is no longer served: it closed, or it stalled (``stalled``)
    ended: asyncio.Event
    #: when its peer was last seen taking bytes (or holding none of ours)
    taken_at: float
    stalled: bool = False
    #: the bytes its peer had not taken at the end of the last pass
    pending_after: int = 0


class LoopFanout:
    """The websocket clients of one event loop for one station: woken by one hand-over from
    the station thread per publication. Directly written clients (``add_direct``) are sent
    what changed in that pass; ASGI-served clients (``add``) have their event set. Subscribed
    to the station's views while it has a client. ``clock``: the loop's by default."""

    def __init__(self, st: Station, loop: asyncio.AbstractEventLoop,
                 clock: Clock | None = None) -> None:
        self.st, self.loop = st, loop
        self.clock: Clock = clock if clock is not None else LoopClock(loop)
        self.events: set[asyncio.Event] = set()
        self.direct: list[DirectClient] = []
        self._unsubscribe: Callable[[], None] | None = None
        self._pending = False
        #: the world's next turn: worlds go at stream.ws_max_hz on average (WORLD_BURST)
        self._world_turn_at = -1e9
        self._world_timer: Timer | None = None
        self._frames_of: Views | None = None  # the views (and parameters) the cached
        self._frames_params = -1  # frames were made of
        self._frames: dict[tuple[str, ...], bytes] = {}
        #: fan-out passes and frames written (for tests and the curious)
        self.passes = 0
        self.writes = 0

    # ---- clients

    def add(self, event: asyncio.Event) -> None:
        self.events.add(event)
        self._subscribe()

    def discard(self, event: asyncio.Event) -> None:
        self.events.discard(event)
        self._unsubscribe_if_idle()

    def add_direct(self, sock: DirectSocket, sent: Views, params_version: int,
                   ended: asyncio.Event) -> DirectClient:
        """Serves ``sock`` from now on; ``sent``: the views its snapshot had (what was
        published since is sent at once); ``ended`` is set when the fan-out stops serving it
        (it closed, or it stalled)."""
        c = DirectClient(sock, sent.world_key, sent.health_mono, sent.geometry_seq,
                         sent.player_serial, params_version, ended, self.clock.now())
        self.direct.append(c)
        self._subscribe()
        if self.st.views.serial != sent.serial or self.st.params.version != params_version:
            self.loop.call_soon(self._pass)  # the others have it already: nothing for them
        return c

    def discard_direct(self, c: DirectClient) -> None:
        if c in self.direct:
            self.direct.remove(c)
        c.ended.set()
        self._unsubscribe_if_idle()

    def _subscribe(self) -> None:
        if self._unsubscribe is None:
            self._unsubscribe = self.st.subscribe_views(self._notify)

    def _unsubscribe_if_idle(self) -> None:
        if not self.events and not self.direct and self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None
            if self._world_timer is not None:
                self._world_timer.cancel()
                self._world_timer = None

    # ---- publications

    def _notify(self) -> None:  # on the station thread: only hand over to the web loop
        if not self._pending:  # one hand-over in flight is enough: it wakes everyone
            self._pending = True
            self.loop.call_soon_threadsafe(self._wake)

    def _wake(self) -> None:
        self._pending = False
        for event in self.events:
            event.set()
        if self.direct:
            self.fan_out()

    def _data(self, v: Views, kinds: tuple[str, ...]) -> bytes:
        """The frames of the messages ``kinds`` of ``v`` ("params", "geometry", "player",
        "world", "health") in one piece, made once for every client that needs the same."""
        if v is not self._frames_of or self.st.params.version != self._frames_params:
            self._frames_of, self._frames_params, self._frames = v, self.st.params.version, {}
        data = self._frames.get(kinds)
        if data is None:
            if len(kinds) == 1:
                data = self._frame(v, kinds[0])
            else:
                data = b"".join(self._data(v, (k,)) for k in kinds)
            self._frames[kinds] = data
        return data

    def _frame(self, v: Views, kind: str) -> bytes:
        if kind == "world":
            text = v.world_json
        elif kind == "health":
            text = v.health_json
        elif kind == "player":
            text = v.player_json
        elif kind == "geometry":
            text = geometry_message(v)
        else:
            text = params_message(self.st)
        return text_frame(text)

    def fan_out(self, world_turn: bool = False) -> None:
        """Sends every directly written client what changed since what it has: parameters,
        geometry, the player, the world (``stream.ws_max_hz`` on average: a world more than
        ``WORLD_BURST`` turns early waits for its turn, then the newest goes), health; in that
        order, in one write. A client whose socket still holds bytes is skipped; one whose
        peer took nothing for ``STALLED_CLIENT_S`` is dropped (``stalled``), its connection
        reset. ``world_turn``: the waiting world's turn has come (its timer)."""
        self.passes += 1
        st = self.st
        v = st.views
        now = self.clock.now()
        period = 1.0 / st.params.current.stream.ws_max_hz
        world_due = world_turn or now >= self._world_turn_at - WORLD_BURST * period
        world_waits = world_sent = False
        params_version = st.params.version
        for c in list(self.direct):
            sock = c.sock
            if not sock.open():
                self.discard_direct(c)
                continue
            pending = sock.pending()
            if pending == 0 or pending < c.pending_after:
                c.taken_at = now  # its peer took something since the last pass
            elif now - c.taken_at >= STALLED_CLIENT_S:
                c.stalled = True
                st.web.dropped += 1
                self.discard_direct(c)
                with contextlib.suppress(RuntimeError, OSError):
                    sock.abort()
                continue
            c.pending_after = pending
            if sock.buffered():
                continue
            kinds: list[str] = []
            if c.params_version != params_version:
                kinds.append("params")
                c.params_version = params_version
            if c.geometry_seq != v.geometry_seq and v.geometry is not None:
                kinds.append("geometry")
                c.geometry_seq = v.geometry_seq
            if c.player_serial != v.player_serial:
                kinds.append("player")
                c.player_serial = v.player_serial
            if c.world_key != v.world_key:
                if world_due:
                    kinds.append("world")
                    c.world_key = v.world_key
                    world_sent = True
                else:
                    world_waits = True
            if c.health_mono != v.health_mono:
                kinds.append("health")
                c.health_mono = v.health_mono
            if kinds:
                data = self._data(v, tuple(kinds))
                try:
                    sock.write(data)
                except (RuntimeError, OSError):  # the connection went meanwhile
                    self.discard_direct(c)
                    continue
                c.pending_after = pending + len(data)
                self.writes += 1
        if world_sent:
            self._world_turn_at = max(self._world_turn_at, now) + period
        if world_waits and self._world_timer is None:
            self._world_timer = self.clock.call_later(
                max(0.0, self._world_turn_at - WORLD_BURST * period - now), self._world_turn)

    def _world_turn(self) -> None:
        self._world_timer = None
        if self.direct:
            self.fan_out(world_turn=True)

    def _pass(self) -> None:
        if self.direct:
            self.fan_out()


_fanouts: weakref.WeakKeyDictionary[Station, dict[asyncio.AbstractEventLoop, LoopFanout]] = (
    weakref.WeakKeyDictionary())


def fanout_of(st: Station) -> LoopFanout:
    """The fan-out of ``st`` on the running loop (made on first use)."""
    loop = asyncio.get_running_loop()
    per_loop = _fanouts.setdefault(st, {})
    for old in [x for x in per_loop
                if x.is_closed() and not per_loop[x].events and not per_loop[x].direct]:
        del per_loop[old]  # a loop that ended (tests start one per client)
    f = per_loop.get(loop)
    if f is None or f.loop.is_closed():
        f = per_loop[loop] = LoopFanout(st, loop)
    return f
