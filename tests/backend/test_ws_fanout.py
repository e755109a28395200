"""A stalled websocket client must not slow the loop or the other clients, and is dropped
after 2 s of taking nothing (real uvicorn)."""

from __future__ import annotations

import asyncio
import base64
import itertools
import json
import os
import socket
import threading
import time

import uvicorn
from websockets.sync.client import connect

from backend.api import create_app
from backend.config import Settings
from backend.station import Station
from backend.world.state import RobotState, WorldState
from launcher.supervisor import free_tcp_port


def _big_world(k: int) -> WorldState:
    robots = tuple(RobotState("blue" if i < 11 else "yellow", i % 11, float(k + i), 0.0, 0.0,
                              t_seen=float(k)) for i in range(22))
    return WorldState(float(k), k, None, robots)


def test_stalled_client_does_not_slow_the_others_and_is_dropped(tmp_path) -> None:  # type: ignore[no-untyped-def]
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
    deadline = time.monotonic() + 10
    while not server.started:
        assert time.monotonic() < deadline, "server did not start"
        time.sleep(0.01)
    loop = loop_box["loop"]
    stop = threading.Event()

    def writer() -> None:  # the world model at 120 Hz
        k = 0
        while not stop.is_set():
            k += 1
            loop.call_soon_threadsafe(st.world_topic.write, _big_world(k))
            stop.wait(1 / 120)

    wt = threading.Thread(target=writer, daemon=True)
    wt.start()
    stalled = []
    try:
        # three clients that complete the handshake and then never read
        for _ in range(3):
            s = socket.socket()
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            s.connect(("127.0.0.1", port))
            keyb = base64.b64encode(os.urandom(16)).decode()
            s.sendall((f"GET /api/ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
                       f"Connection: Upgrade\r\nSec-WebSocket-Key: {keyb}\r\n"
                       "Sec-WebSocket-Version: 13\r\n\r\n").encode())
            stalled.append(s)
        with connect(f"ws://127.0.0.1:{port}/api/ws", max_size=None) as ws:
            t_end = time.monotonic() + 4.0
            stamps: list[float] = []
            seqs: list[int] = []
            while time.monotonic() < t_end:
                msg = json.loads(ws.recv(timeout=2.0))
                if msg["type"] == "world":
                    stamps.append(time.monotonic())
                    seqs.append(msg["world"]["seq"])
        # the last 2 s, when the stalled clients' buffers are long full: new worlds (a world
        # is also re-sent when only its referee part changed, so distinct frames are counted)
        late = {q for t, q in zip(stamps, seqs, strict=True) if t > t_end - 2.0}
        # a fan-out that waits for the stalled clients delivers nothing once their buffers
        # are full; 5 new worlds/s is far above that and far below what a loaded 2-core CI
        # machine still gives (the rate itself is measured in bench/ws_fanout.py)
        assert len(late) / 2.0 >= 5.0, f"only {len(late) / 2.0:.1f} new worlds/s"
        assert seqs == sorted(seqs)  # the latest only, in order
        # uvicorn's connections are written by the fan-out directly (not through ASGI)
        from backend.wsfanout import _fanouts
        assert sum(f.writes for f in _fanouts[st].values()) >= len(seqs)
        # the stalled clients are dropped (their socket took nothing for 2 s): counted, and
        # their connections closed by the server (a read ends once their buffers are drained)
        deadline = time.monotonic() + 20
        while st.ws_dropped < 3:
            assert time.monotonic() < deadline, f"dropped {st.ws_dropped} of 3 stalled clients"
            time.sleep(0.05)
        for s in stalled:
            s.settimeout(5.0)
            for _ in range(100_000):  # bounded: the buffers hold a few hundred KB
                if not s.recv(65536):
                    break
            else:
                raise AssertionError("a dropped client's connection stayed open")
        assert st.ws_clients == 0
    finally:
        stop.set()
        wt.join()
        for s in stalled:
            s.close()
        server.should_exit = True
        th.join(timeout=10)


class _Views:
    """The station's ``subscribe_views`` contract: listeners called on another thread."""

    def __init__(self) -> None:
        self.listeners: set = set()  # type: ignore[type-arg]

    def subscribe_views(self, listener):  # type: ignore[no-untyped-def]
        self.listeners.add(listener)
        return lambda: self.listeners.discard(listener)


def test_all_clients_of_a_loop_are_woken_by_one_hand_over_per_publication() -> None:
    from backend.wsfanout import LoopFanout

    views = _Views()

    async def run() -> None:
        loop = asyncio.get_running_loop()
        w = LoopFanout(views, loop)  # type: ignore[arg-type]
        events = [asyncio.Event() for _ in range(25)]
        for e in events:
            w.add(e)
        assert len(views.listeners) == 1  # one subscription for the loop, not one per client
        handed: list[object] = []
        real = loop.call_soon_threadsafe

        def counting(cb, *args):  # type: ignore[no-untyped-def]
            handed.append(cb)
            return real(cb, *args)

        loop.call_soon_threadsafe = counting  # type: ignore[method-assign]
        listener = next(iter(views.listeners))
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
        assert not views.listeners  # the last client gone: unsubscribed

    asyncio.run(run())


# ---- the direct fan-out (backend.wsfanout.LoopFanout) with sockets and a station of its own


class _Sock:
    """A ``DirectSocket`` stand-in: what was written, and bytes it has not taken."""

    def __init__(self) -> None:
        self.writes: list[bytes] = []
        self.pending = 0
        self.closed = False

    def open(self) -> bool:
        return not self.closed

    def buffered(self) -> int:
        return self.pending

    def write(self, data: bytes) -> None:
        self.writes.append(data)


class _Station(_Views):
    """What the fan-out reads of a station: the views, the parameters."""

    def __init__(self, hz: float = 50.0) -> None:
        from types import SimpleNamespace

        from backend.viewhub import Views
        super().__init__()
        self.views = Views()
        values = {"x": 1}
        self.params = SimpleNamespace(version=0, values=lambda: values,
                                      current=SimpleNamespace(stream=SimpleNamespace(
                                          ws_max_hz=hz)))

    def publish(self, **changes) -> None:  # type: ignore[no-untyped-def]
        from dataclasses import replace
        self.views = replace(self.views, serial=self.views.serial + 1, **changes)
        for listener in list(self.listeners):
            listener()


def _world(k: int) -> dict:  # type: ignore[type-arg]
    return {"world_key": (k,), "world_json": json.dumps({"type": "world", "world": {"seq": k}})}


def _frames(data: bytes) -> list[dict]:  # type: ignore[type-arg]
    """The JSON messages of unmasked text frames."""
    from websockets.frames import Frame
    from websockets.streams import StreamReader
    reader = StreamReader()
    reader.feed_data(data)
    out = []
    while reader.buffer:
        gen = Frame.parse(reader.read_exact, mask=False)
        try:
            next(gen)
        except StopIteration as stop:
            out.append(json.loads(stop.value.data))
    return out


def _fanout(st: _Station, n: int):  # type: ignore[no-untyped-def]
    from backend.wsfanout import LoopFanout
    loop = asyncio.get_running_loop()
    f = LoopFanout(st, loop)  # type: ignore[arg-type]
    socks = [_Sock() for _ in range(n)]
    clients = [f.add_direct(s, st.views, st.params.version, asyncio.Event())  # type: ignore[arg-type]
               for s in socks]
    return f, socks, clients


def test_one_publication_is_framed_once_and_written_to_every_client_in_one_pass() -> None:
    async def run() -> None:
        st = _Station(hz=1000.0)
        f, socks, _ = _fanout(st, 25)
        assert len(st.listeners) == 1
        st.publish(**_world(1), health_json='{"type":"health","health":{}}', health_mono=5.0)
        await asyncio.sleep(0)  # the hand-over runs
        assert f.passes == 1
        assert all(len(s.writes) == 1 for s in socks)
        first = socks[0].writes[0]
        assert all(s.writes[0] is first for s in socks)  # the same bytes, made once
        assert [m["type"] for m in _frames(first)] == ["world", "health"]  # in one write
        await asyncio.sleep(0.01)  # the next world's turn
        for _ in range(3):  # three publications before the loop runs: one pass, the newest
            st.publish(**_world(2))
        await asyncio.sleep(0.05)
        assert f.passes == 2
        newest = [{"type": "world", "world": {"seq": 2}}]
        assert [_frames(s.writes[-1]) for s in socks] == [newest] * 25

    asyncio.run(run())


def test_a_client_that_has_not_taken_its_bytes_is_skipped_then_gets_the_newest() -> None:
    async def run() -> None:
        st = _Station(hz=1000.0)
        _f, (slow, fast), _ = _fanout(st, 2)
        slow.pending = 1000
        for k in (1, 2, 3):
            st.publish(**_world(k))
            await asyncio.sleep(0.01)
        assert [_frames(w)[0]["world"]["seq"] for w in fast.writes] == [1, 2, 3]
        assert slow.writes == []  # nothing queued behind what it holds
        slow.pending = 0
        st.publish(health_json='{"type":"health","health":{}}', health_mono=1.0)
        await asyncio.sleep(0.01)
        # it catches up with the newest world only (and what else changed)
        assert [m["type"] for m in _frames(slow.writes[0])] == ["world", "health"]
        assert _frames(slow.writes[0])[0]["world"]["seq"] == 3

    asyncio.run(run())


def test_a_client_that_takes_nothing_for_two_seconds_is_dropped(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from backend import wsfanout
    clock = [100.0]
    monkeypatch.setattr(wsfanout.time, "monotonic", lambda: clock[0])

    async def run() -> None:
        st = _Station(hz=1000.0)
        f, (stuck, draining, ok), clients = _fanout(st, 3)
        stuck.pending = draining.pending = 50_000
        for k in range(1, 30):  # 2.8 s of publications, 0.1 s apart
            clock[0] += 0.1
            draining.pending -= 1000  # it takes a little at a time: not stalled
            st.publish(**_world(k))
            await asyncio.sleep(0)
            if clock[0] - 100.0 < wsfanout.STALLED_CLIENT_S:
                assert not clients[0].ended.is_set()
        assert clients[0].stalled and clients[0].ended.is_set()
        assert not clients[1].stalled and not clients[1].ended.is_set()
        assert len(ok.writes) == 29
        assert f.direct == clients[1:]
        stuck.pending = 0
        st.publish(**_world(99))
        await asyncio.sleep(0)
        assert stuck.writes == []  # dropped: never written again

    asyncio.run(run())


def test_worlds_go_out_at_most_at_ws_max_hz_the_newest_in_their_turn() -> None:
    async def run() -> None:
        st = _Station(hz=20.0)  # a turn every 50 ms
        _f, (s,), _ = _fanout(st, 1)
        loop = asyncio.get_running_loop()
        stamps: list[float] = []
        real_write = s.write

        def write(data: bytes) -> None:
            stamps.append(loop.time())
            real_write(data)
        s.write = write  # type: ignore[method-assign]
        for k in range(1, 21):  # 200 Hz of new worlds for 0.1 s
            st.publish(**_world(k))
            await asyncio.sleep(0.005)
        await asyncio.sleep(0.1)  # the last turn
        seqs = [_frames(w)[0]["world"]["seq"] for w in s.writes]
        assert 2 <= len(seqs) <= 4, seqs
        assert seqs == sorted(seqs) and seqs[-1] == 20  # the newest goes in the last turn
        gaps = [b - a for a, b in itertools.pairwise(stamps)]
        assert min(gaps) >= 0.05 * (1 - 0.25) - 0.002, gaps

    asyncio.run(run())


def test_a_player_change_goes_out_while_the_world_waits_for_its_turn() -> None:
    async def run() -> None:
        st = _Station(hz=1.0)
        f, (s,), _ = _fanout(st, 1)
        st.publish(**_world(1))
        await asyncio.sleep(0.01)
        st.publish(**_world(2))
        await asyncio.sleep(0.01)
        st.publish(player_json='{"type":"player","player":{"error":"marker"}}', player_serial=1)
        await asyncio.sleep(0.01)
        assert [[m["type"] for m in _frames(w)] for w in s.writes] == [["world"], ["player"]]
        st.params.version = 3  # type: ignore[attr-defined]
        st.publish(**_world(3))
        await asyncio.sleep(0.01)
        assert _frames(s.writes[-1]) == [{"type": "params", "version": 3, "values": {"x": 1}}]
        for c in list(f.direct):
            f.discard_direct(c)
        assert not st.listeners and f._world_timer is None  # the waiting world's timer too

    asyncio.run(run())
