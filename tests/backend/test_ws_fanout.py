"""A stalled websocket client must not slow the loop or the other clients, and is dropped
after 2 s of taking nothing (real uvicorn)."""

from __future__ import annotations

import asyncio
import base64
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
    from backend.routes.ws import _LoopWakeups

    views = _Views()

    async def run() -> None:
        loop = asyncio.get_running_loop()
        w = _LoopWakeups(views, loop)  # type: ignore[arg-type]
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
