"""The websocket fan-out (backend/wsfanout.py): every reading client gets the stream whoever
else is connected, a client that stops reading is dropped within 2 s of its last read and
counted. Time is the fan-out's injected clock (``FakeClock``), the sockets fake transports
that take what is written as their peer reads; one test goes through the real server
(uvicorn, real websocket clients) with bounded waits and no timing."""

from __future__ import annotations

import asyncio
import base64
import heapq
import itertools
import json
import os
import random
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from types import SimpleNamespace
from typing import Any

import pytest
import uvicorn
from websockets.frames import Frame
from websockets.streams import StreamReader
from websockets.sync.client import connect

from backend.api import create_app
from backend.config import Settings
from backend.station import Station
from backend.viewhub import Views, WebStats
from backend.world.state import RobotState, WorldState
from backend.wsfanout import STALLED_CLIENT_S, DirectSocket, LoopFanout
from launcher.supervisor import free_tcp_port

# ---- the real server


def _big_world(k: int) -> WorldState:
    robots = tuple(RobotState("blue" if i < 11 else "yellow", i % 11, float(k + i), 0.0, 0.0,
                              t_seen=float(k)) for i in range(22))
    return WorldState(float(k), k, None, robots)


def _stalled_client(port: int) -> socket.socket:
    """A websocket client that completes the handshake and never reads a byte."""
    s = socket.socket()
    s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    s.connect(("127.0.0.1", port))
    key = base64.b64encode(os.urandom(16)).decode()
    s.sendall((f"GET /api/ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
               f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
               "Sec-WebSocket-Version: 13\r\n\r\n").encode())
    return s


def _established(s: socket.socket) -> bool:
    """Whether the connection's TCP state is still ESTABLISHED (no reset, no close arrived)."""
    return bool(s.getsockopt(socket.IPPROTO_TCP, socket.TCP_INFO, 1)[0] == 1)


def _closed_by_server(s: socket.socket) -> bool:
    """Reads what the server had sent until the connection ends (reset, or closed after it);
    False if it is still open after that."""
    s.settimeout(5.0)
    try:
        for _ in range(100_000):  # bounded: its buffers hold at most a few MB
            if not s.recv(65536):
                return True
    except ConnectionResetError:
        return True
    except TimeoutError:
        return False
    return False


def test_a_stalled_client_is_dropped_and_the_others_keep_receiving(tmp_path) -> None:  # type: ignore[no-untyped-def]
    port = free_tcp_port()
    settings = Settings(port=port, relay_pub=f"tcp://127.0.0.1:{free_tcp_port()}",
                        relay_sub=f"tcp://127.0.0.1:{free_tcp_port()}", static_dir=tmp_path,
                        state_dir=tmp_path / "state")
    st = Station(settings)
    server = uvicorn.Server(uvicorn.Config(create_app(settings, st), host="127.0.0.1", port=port,
                                           ws_per_message_deflate=False, log_level="warning"))
    loop_box: dict[str, asyncio.AbstractEventLoop] = {}

    def serve() -> None:
        loop = asyncio.new_event_loop()
        loop_box["loop"] = loop
        loop.run_until_complete(server.serve())

    th = threading.Thread(target=serve, daemon=True)
    th.start()
    stop = threading.Event()
    deadline = time.monotonic() + 10
    while not server.started:  # uvicorn's own flag: no event to wait on
        assert time.monotonic() < deadline, "server did not start"
        stop.wait(0.01)
    loop = loop_box["loop"]

    def writer() -> None:  # the world model at 120 Hz: the source's pace, not a wait
        k = 0
        while not stop.is_set():
            k += 1
            loop.call_soon_threadsafe(st.world_topic.write, _big_world(k))
            stop.wait(1 / 120)

    wt = threading.Thread(target=writer, daemon=True)
    wt.start()
    stalled: list[socket.socket] = []
    try:
        with connect(f"ws://127.0.0.1:{port}/api/ws", max_size=None) as ws:
            assert json.loads(ws.recv(timeout=10))["type"] == "snapshot"
            stalled = [_stalled_client(port) for _ in range(3)]
            while_stalled: set[int] = set()  # new worlds while the stalled are connected
            after: set[int] = set()
            seqs: list[int] = []
            deadline = time.monotonic() + 60
            while len(after) < 20:
                assert time.monotonic() < deadline, (
                    f"dropped {st.web.dropped} of 3 stalled clients, {len(after)} worlds after")
                msg = json.loads(ws.recv(timeout=10))  # the others keep receiving
                if msg["type"] != "world":
                    continue
                seqs.append(msg["world"]["seq"])
                (after if st.web.dropped >= 3 else while_stalled).add(msg["world"]["seq"])
        # worlds kept coming while the stalled clients were there (they are there >= 1.5 s)
        assert len(while_stalled) >= 10, while_stalled
        assert seqs == sorted(seqs)  # the latest only, in order
        assert st.web.dropped == 3
        # uvicorn's connections are written by the fan-out directly (not through ASGI)
        from backend.wsfanout import _fanouts
        assert sum(f.writes for f in _fanouts[st].values()) >= len(seqs)
        # the dropped clients' connections are reset by the server without a byte read: a
        # close queued behind the data they never took would leave them open, and the
        # server's kernel holding megabytes for each
        deadline = time.monotonic() + 10
        while any(_established(s) for s in stalled):
            assert time.monotonic() < deadline, "a dropped client's connection was not reset"
            stop.wait(0.01)
        for s in stalled:
            assert _closed_by_server(s)
        deadline = time.monotonic() + 10
        while st.web.clients:  # the reader's endpoint ends once its close is handled
            assert time.monotonic() < deadline, f"{st.web.clients} clients left"
            stop.wait(0.01)
    finally:
        stop.set()
        wt.join()
        for s in stalled:
            s.close()
        server.should_exit = True
        th.join(timeout=10)


# ---- the fan-out on an injected clock, with fake transports


class FakeClock:
    """The fan-out's clock, driven by the test. ``timer_late``: a loaded loop runs its timers
    late, by up to this (seeded, uniform)."""

    def __init__(self, t: float = 100.0, timer_late: float = 0.0, seed: int = 1) -> None:
        self.t = t
        self.timer_late = timer_late
        self.rng = random.Random(seed)
        self._timers: list[tuple[float, int, FakeTimer]] = []
        self._seq = itertools.count()

    def now(self) -> float:
        return self.t

    def call_later(self, delay: float, callback: Callable[[], None]) -> FakeTimer:
        timer = FakeTimer(callback)
        when = self.t + max(0.0, delay) + self.rng.uniform(0.0, self.timer_late)
        heapq.heappush(self._timers, (when, next(self._seq), timer))
        return timer

    def next_timer(self) -> float | None:
        while self._timers and self._timers[0][2].cancelled:
            heapq.heappop(self._timers)
        return self._timers[0][0] if self._timers else None

    def advance(self, to: float) -> None:
        """Runs the timers due until ``to``, each at its time, then sets the clock to ``to``."""
        while (when := self.next_timer()) is not None and when <= to:
            _, _, timer = heapq.heappop(self._timers)
            self.t = max(self.t, when)
            timer.callback()
        self.t = max(self.t, to)


class FakeTimer:
    def __init__(self, callback: Callable[[], None]) -> None:
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        self.cancelled = True


class FakeSocket:
    """A ``DirectSocket`` on the fake clock. Its peer reads everything at once until
    ``reads_until`` (for ever by default), then nothing; its kernel acknowledges up to
    ``window`` bytes more (its receive buffer), and the sending kernel holds ``kernel``
    bytes the peer has not acknowledged before any wait in the user-space buffer."""

    def __init__(self, clock: FakeClock, reads_until: float = float("inf"),
                 window: int = 128 * 1024, kernel: int = 4 * 1024 * 1024) -> None:
        self.clock, self.reads_until = clock, reads_until
        self.window, self.kernel = window, kernel
        self.writes: list[bytes] = []
        self.written = self.read = self.acked = 0
        self.acked_at = clock.now()  # when its peer last took (acknowledged) bytes
        self.aborted = False

    def _catch_up(self) -> None:
        if self.clock.now() < self.reads_until:
            self.read = self.written
        acked = min(self.written, self.read + self.window)
        if acked > self.acked:
            self.acked, self.acked_at = acked, self.clock.now()

    def open(self) -> bool:
        return not self.aborted

    def pending(self) -> int:
        self._catch_up()
        return self.written - self.acked

    def buffered(self) -> int:
        return max(0, self.pending() - self.kernel)

    def write(self, data: bytes) -> None:
        assert not self.aborted
        self._catch_up()
        self.writes.append(data)
        self.written += len(data)
        self._catch_up()

    def abort(self) -> None:
        self.aborted = True


class FakeStation:
    """What the fan-out reads of a station: the views, the parameters; ``publish`` calls the
    subscribers as the station thread does (they hand over to the loop)."""

    def __init__(self, hz: float = 60.0) -> None:
        self.views = Views()
        self.listeners: set[Callable[[], None]] = set()
        self.web = WebStats()
        values = {"x": 1}
        self.params = SimpleNamespace(version=0, values=lambda: values,
                                      current=SimpleNamespace(stream=SimpleNamespace(
                                          ws_max_hz=hz)))

    def subscribe_views(self, listener: Callable[[], None]) -> Callable[[], None]:
        self.listeners.add(listener)
        return lambda: self.listeners.discard(listener)

    def publish(self, **changes: Any) -> None:
        self.views = replace(self.views, serial=self.views.serial + 1, **changes)
        for listener in list(self.listeners):
            listener()


PAD = "x" * 25_000  # a world message of the full game's size (~25 kB)


def _world(k: int, pad: str = "") -> dict[str, Any]:
    return {"world_key": (k,),
            "world_json": json.dumps({"type": "world", "world": {"seq": k, "pad": pad}})}


_parsed: dict[bytes, list[dict[str, Any]]] = {}


def _frames(data: bytes) -> list[dict[str, Any]]:
    """The JSON messages of unmasked text frames (the same bytes parsed once)."""
    out = _parsed.get(data)
    if out is None:
        reader = StreamReader()
        reader.feed_data(data)
        out = []
        while reader.buffer:
            gen = Frame.parse(reader.read_exact, mask=False)
            try:
                next(gen)
            except StopIteration as stop:
                out.append(json.loads(stop.value.data))
        _parsed[data] = out
    return out


def _worlds(s: FakeSocket) -> list[int]:
    return [m["world"]["seq"] for w in s.writes for m in _frames(w) if m["type"] == "world"]


async def _handed_over(f: LoopFanout) -> None:
    """Lets the loop run the hand-over of the publications made (``call_soon_threadsafe``)."""
    for _ in range(100):
        if not f._pending:
            return
        await asyncio.sleep(0)  # one turn of the loop: not time
    raise AssertionError("the hand-over did not run")


def _fanout(st: FakeStation, clock: FakeClock, socks: list[FakeSocket]) -> tuple[
        LoopFanout, list[Any]]:
    f = LoopFanout(st, asyncio.get_running_loop(), clock)  # type: ignore[arg-type]
    clients = [f.add_direct(s, st.views, st.params.version, asyncio.Event())  # type: ignore[arg-type]
               for s in socks]
    return f, clients


@pytest.mark.parametrize("readers", [1, 17, 25])
def test_every_reader_gets_the_stream_beside_stalled_clients_on_a_loaded_loop(
        readers: int) -> None:
    """60 Hz of worlds published late by up to 0.9 of a period (the station's thread busy),
    the loop's timers late by as much: each reader gets >= 90 % of the worlds published,
    while three clients stop reading at 0.5 s, are dropped within 2 s of it and counted."""
    hz, seconds, stop_at = 60.0, 10.0, 0.5

    async def run() -> None:
        period = 1.0 / hz
        clock = FakeClock(timer_late=0.9 * period, seed=readers)
        t0 = clock.now()
        st = FakeStation(hz)
        rng = random.Random(7)
        stalled = [FakeSocket(clock, reads_until=t0 + stop_at) for _ in range(3)]
        reading = [FakeSocket(clock) for _ in range(readers)]
        f, clients = _fanout(st, clock, stalled + reading)
        dropped_at: dict[int, float] = {}
        n = int(seconds * hz)
        for k in range(1, n + 1):
            clock.advance(t0 + k * period + rng.uniform(0.0, 0.9 * period))
            st.publish(**_world(k, PAD))
            await _handed_over(f)
            for i, c in enumerate(clients[:3]):
                if c.ended.is_set() and i not in dropped_at:
                    dropped_at[i] = clock.now()
        clock.advance(clock.now() + 1.0)  # the last world's turn
        for s in reading:
            got = _worlds(s)
            assert got == sorted(set(got))  # each world once, in order, the newest last
            assert got[-1] == n
            assert len(got) >= 0.9 * n, f"{len(got)} of {n} worlds"
        assert all(s.aborted for s in stalled) and not any(s.aborted for s in reading)
        assert all(c.stalled for c in clients[:3])
        assert not any(c.ended.is_set() for c in clients[3:])
        assert st.web.dropped == 3
        assert max(dropped_at.values()) - (t0 + stop_at) <= 2.0, dropped_at

    asyncio.run(run())


def test_a_client_whose_peer_takes_nothing_is_dropped_within_two_seconds() -> None:
    """At the full stream, a client that reads nothing is dropped within 2 s (its kernel's
    queue holds megabytes: the user-space buffer stays empty for seconds), STALLED_CLIENT_S
    after its peer took its last byte; one that takes a little at a time is kept."""

    async def run() -> None:
        clock = FakeClock()
        t0 = clock.now()
        st = FakeStation(hz=60.0)
        stuck = FakeSocket(clock, reads_until=t0)  # from the start
        slow = FakeSocket(clock, reads_until=t0)
        ok = FakeSocket(clock)
        f, clients = _fanout(st, clock, [stuck, slow, ok])
        k = 0
        while not clients[0].ended.is_set():
            k += 1
            assert k < 600, "not dropped in 10 s"
            clock.advance(t0 + k / 60)
            slow.read += 1000  # it takes a little at a time: not stalled
            st.publish(**_world(k, PAD))
            await _handed_over(f)
        assert clock.now() - t0 <= 2.0
        assert clock.now() - stuck.acked_at >= STALLED_CLIENT_S  # not before its time
        assert clients[0].stalled and stuck.aborted and st.web.dropped == 1
        assert not clients[1].ended.is_set() and not clients[2].ended.is_set()
        assert f.direct == clients[1:]
        n = len(stuck.writes)
        st.publish(**_world(k + 1))
        await _handed_over(f)
        assert len(stuck.writes) == n  # dropped: never written again
        assert _worlds(ok)[-1] == k + 1

    asyncio.run(run())


def test_a_client_that_holds_unsent_bytes_is_skipped_then_gets_the_newest() -> None:
    async def run() -> None:
        clock = FakeClock()
        st = FakeStation(hz=10.0)
        slow, fast = FakeSocket(clock, reads_until=clock.now(), kernel=0, window=0), \
            FakeSocket(clock)
        f, _ = _fanout(st, clock, [slow, fast])
        slow.written = 1000  # bytes of its own it has not taken (its snapshot)
        for k in (1, 2, 3):
            clock.advance(clock.now() + 0.1)
            st.publish(**_world(k))
            await _handed_over(f)
        assert _worlds(fast) == [1, 2, 3]
        assert slow.writes == []  # nothing queued behind what it holds
        slow.read = slow.written  # it took them
        slow.reads_until = float("inf")
        clock.advance(clock.now() + 0.1)
        st.publish(health_json='{"type":"health","health":{}}', health_mono=1.0)
        await _handed_over(f)
        # it catches up with the newest world only (and what else changed)
        assert [m["type"] for m in _frames(slow.writes[0])] == ["world", "health"]
        assert _frames(slow.writes[0])[0]["world"]["seq"] == 3

    asyncio.run(run())


def test_one_publication_is_framed_once_and_written_to_every_client_in_one_pass() -> None:
    async def run() -> None:
        clock = FakeClock()
        st = FakeStation(hz=60.0)
        socks = [FakeSocket(clock) for _ in range(25)]
        f, _ = _fanout(st, clock, socks)
        assert len(st.listeners) == 1
        st.publish(**_world(1), health_json='{"type":"health","health":{}}', health_mono=5.0)
        await _handed_over(f)
        assert f.passes == 1
        assert all(len(s.writes) == 1 for s in socks)
        first = socks[0].writes[0]
        assert all(s.writes[0] is first for s in socks)  # the same bytes, made once
        assert [m["type"] for m in _frames(first)] == ["world", "health"]  # in one write
        clock.advance(clock.now() + 1 / 60)
        for k in (2, 3, 4):  # three publications before the loop runs: one pass, the newest
            st.publish(**_world(k))
        await _handed_over(f)
        assert f.passes == 2
        assert [_frames(s.writes[-1]) for s in socks] == [
            [{"type": "world", "world": {"seq": 4, "pad": ""}}]] * 25

    asyncio.run(run())


def test_worlds_go_out_at_ws_max_hz_the_newest_in_their_turn() -> None:
    """Published at 200 Hz for 2 s: 20 Hz go out (plus the burst a late world may take), a
    period apart once the burst is spent, the newest in each turn."""

    async def run() -> None:
        clock = FakeClock()
        t0 = clock.now()
        st = FakeStation(hz=20.0)
        (s,) = socks = [FakeSocket(clock)]
        f, _ = _fanout(st, clock, socks)
        stamps: list[float] = []
        real_write = s.write

        def write(data: bytes) -> None:
            stamps.append(clock.now())
            real_write(data)

        s.write = write  # type: ignore[method-assign]
        for k in range(1, 401):
            clock.advance(t0 + k * 0.005)
            st.publish(**_world(k))
            await _handed_over(f)
        clock.advance(clock.now() + 1.0)  # the last turn
        seqs = _worlds(s)
        assert seqs == sorted(seqs) and seqs[-1] == 400  # the newest goes in the last turn
        assert 40 <= len(seqs) <= 40 + 3, seqs  # 2 s at 20 Hz, and at most the burst
        gaps = [b - a for a, b in itertools.pairwise(stamps)]
        assert min(gaps[3:]) >= 0.05 - 1e-9, gaps  # the burst spent: a period apart

    asyncio.run(run())


def test_a_player_change_goes_out_while_the_world_waits_for_its_turn() -> None:
    async def run() -> None:
        clock = FakeClock()
        st = FakeStation(hz=1.0)
        (s,) = socks = [FakeSocket(clock)]
        f, _ = _fanout(st, clock, socks)
        k = 0
        while not f._world_timer:  # the burst spent: a world waits for its turn
            k += 1
            assert k < 10
            st.publish(**_world(k))
            await _handed_over(f)
        sent = len(s.writes)
        st.publish(player_json='{"type":"player","player":{"error":"marker"}}',
                   player_serial=1)
        await _handed_over(f)
        assert [m["type"] for m in _frames(s.writes[-1])] == ["player"]
        assert len(s.writes) == sent + 1
        st.params.version = 3
        st.publish(**_world(k + 1))
        await _handed_over(f)
        assert _frames(s.writes[-1]) == [{"type": "params", "version": 3, "values": {"x": 1}}]
        clock.advance(clock.now() + 10.0)  # its turn: the newest world
        assert _worlds(s)[-1] == k + 1
        for c in list(f.direct):
            f.discard_direct(c)
        assert not st.listeners and f._world_timer is None  # the waiting world's timer too

    asyncio.run(run())


def test_all_clients_of_a_loop_are_woken_by_one_hand_over_per_publication() -> None:
    st = FakeStation()

    async def run() -> None:
        loop = asyncio.get_running_loop()
        w = LoopFanout(st, loop)  # type: ignore[arg-type]
        events = [asyncio.Event() for _ in range(25)]
        for e in events:
            w.add(e)
        assert len(st.listeners) == 1  # one subscription for the loop, not one per client
        handed: list[object] = []
        real = loop.call_soon_threadsafe

        def counting(cb, *args):  # type: ignore[no-untyped-def]
            handed.append(cb)
            return real(cb, *args)

        loop.call_soon_threadsafe = counting  # type: ignore[method-assign]
        listener = next(iter(st.listeners))
        t = threading.Thread(target=lambda: [listener() for _ in range(3)])
        t.start()
        t.join()
        await asyncio.wait_for(asyncio.gather(*(e.wait() for e in events)), 5.0)
        assert len(handed) == 1  # three publications before the loop ran: one hand-over
        for e in events:
            e.clear()
        listener()  # the next publication after the wake-up hands over again
        await asyncio.wait_for(asyncio.gather(*(e.wait() for e in events)), 5.0)
        assert len(handed) == 2
        for e in events:
            w.discard(e)
        assert not st.listeners  # the last client gone: unsubscribed

    asyncio.run(run())


# ---- DirectSocket on a real TCP connection


def test_a_direct_socket_counts_what_its_peer_has_not_taken() -> None:
    """``pending`` counts the bytes in the kernel the peer has not acknowledged: they grow
    while the peer reads nothing (the user-space buffer empty meanwhile), and go to 0 once it
    reads."""

    async def run() -> None:
        accepted: asyncio.Future[asyncio.Transport] = asyncio.get_running_loop().create_future()

        class Proto(asyncio.Protocol):
            def connection_made(self, transport: asyncio.BaseTransport) -> None:
                accepted.set_result(transport)  # type: ignore[arg-type]

        server = await asyncio.get_running_loop().create_server(Proto, "127.0.0.1", 0)
        port = server.sockets[0].getsockname()[1]
        peer = socket.create_connection(("127.0.0.1", port))
        peer.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        try:
            transport = await asyncio.wait_for(accepted, 5.0)
            sock = DirectSocket(SimpleNamespace(transport=transport))
            assert sock.pending() == 0
            sock.write(b"x" * 200_000)
            assert sock.pending() > sock.buffered()  # the kernel's unacknowledged bytes
            peer.settimeout(5.0)

            def read_all() -> None:  # on a thread: the loop flushes the transport meanwhile
                got = 0
                while got < 200_000:
                    got += len(peer.recv(65536))

            await asyncio.to_thread(read_all)
            for _ in range(1000):  # the acknowledgements arrive (a loopback round trip)
                if sock.pending() == 0:
                    break
                await asyncio.sleep(0.001)
            assert sock.pending() == 0
            transport.close()
        finally:
            peer.close()
            server.close()
            await server.wait_closed()

    asyncio.run(run())
