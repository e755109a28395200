"""The websocket ``/api/ws``: a snapshot, then every change of the station's published views.
The station notifies; this loop never polls its state."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
import weakref
from collections.abc import Callable
from dataclasses import replace

from fastapi import APIRouter, WebSocket
from starlette.websockets import WebSocketDisconnect, WebSocketState

from sslnet.ratelog import RateLimitedLog

from ..jsonsafe import dumps
from ..station import Station
from .deps import VIEWER, StationDep
from .operators import ws_session

log = logging.getLogger("touchline.api")
_ws_log = RateLimitedLog(log, interval_s=10.0)

router = APIRouter(prefix="/api", tags=["websocket"])


@router.websocket("/ws", dependencies=[VIEWER])
async def ws_endpoint(ws: WebSocket, st: StationDep) -> None:
    # Host and Origin were checked by the EdgeGuard, the token by the AccessGuard (which
    # refuses a websocket before it is accepted) and again by the VIEWER dependency
    await ws.accept()
    st.ws_clients += 1
    try:
        with ws_session(ws, st):
            await _serve_client(ws, st)
    except (WebSocketDisconnect, RuntimeError, ConnectionError):
        pass
    finally:
        st.ws_clients -= 1


#: a websocket client whose socket takes no message for this long is dropped (it reconnects
#: and gets a snapshot): it no longer slows anyone, but it held its buffers for ever
STALLED_CLIENT_S = 2.0


class _Stalled(Exception):
    pass


async def _serve_client(ws: WebSocket, st: Station) -> None:
    """Sends a snapshot, then every change of the station's published views: the latest world
    at up to ``stream.ws_max_hz`` (a slow client only delays itself: it always gets the newest
    world, never a backlog), parameters and geometry when they change, health as published
    (about four times a second). The station notifies; this loop never polls its state. A
    client that takes nothing for ``STALLED_CLIENT_S`` is dropped."""
    try:
        await _serve_views(ws, st)
    except _Stalled:
        st.ws_dropped += 1
        peer = f"{ws.client.host}:{ws.client.port}" if ws.client else "?"
        _ws_log.warning("stalled", "websocket client %s took nothing for %.0f s: dropped "
                        "(%d so far)", peer, STALLED_CLIENT_S, st.ws_dropped)


class _LoopWakeups:
    """Wakes every websocket client of one event loop with one hand-over from the station
    thread per publication (not one ``call_soon_threadsafe`` per client: 25 clients at 60 Hz
    were 1500 self-pipe writes and loop wake-ups a second). Subscribed to the station's views
    while it has a client."""

    def __init__(self, st: Station, loop: asyncio.AbstractEventLoop) -> None:
        self.st, self.loop = st, loop
        self.events: set[asyncio.Event] = set()
        self._unsubscribe: Callable[[], None] | None = None
        self._pending = False

    def add(self, event: asyncio.Event) -> None:
        self.events.add(event)
        if self._unsubscribe is None:
            self._unsubscribe = self.st.subscribe_views(self._notify)

    def discard(self, event: asyncio.Event) -> None:
        self.events.discard(event)
        if not self.events and self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None

    def _notify(self) -> None:  # on the station thread: only hand over to the web loop
        if not self._pending:  # one hand-over in flight is enough: it wakes everyone
            self._pending = True
            self.loop.call_soon_threadsafe(self._wake)

    def _wake(self) -> None:
        self._pending = False
        for event in self.events:
            event.set()


_wakeups: weakref.WeakKeyDictionary[Station, dict[asyncio.AbstractEventLoop, _LoopWakeups]] = (
    weakref.WeakKeyDictionary())


def _wakeups_of(st: Station) -> _LoopWakeups:
    loop = asyncio.get_running_loop()
    per_loop = _wakeups.setdefault(st, {})
    for old in [x for x in per_loop if x.is_closed() and not per_loop[x].events]:
        del per_loop[old]  # a loop that ended (tests start one per client)
    w = per_loop.get(loop)
    if w is None or w.loop.is_closed():
        w = per_loop[loop] = _LoopWakeups(st, loop)
    return w


async def _serve_views(ws: WebSocket, st: Station) -> None:
    async def send(text: str) -> None:
        try:
            async with asyncio.timeout(STALLED_CLIENT_S):  # no task per send (wait_for makes one)
                await ws.send_text(text)
        except TimeoutError:
            raise _Stalled from None

    closed = asyncio.Event()
    changed = asyncio.Event()
    wakeups = _wakeups_of(st)
    wakeups.add(changed)

    async def receive() -> None:
        try:
            while True:
                msg = await ws.receive()
                if msg["type"] == "websocket.disconnect":
                    break
        finally:
            closed.set()
            changed.set()

    rx = asyncio.create_task(receive())
    try:
        await st.read(st.publish_views, True)  # fresh for this client (none may have been)
        v = st.views
        params_version = st.params.version
        await send(dumps({
            "type": "snapshot", "world": v.world, "geometry": v.geometry, "health": v.health,
            "params": {"version": params_version, "values": st.params.values()},
            "player": v.player,
        }, "snapshot"))
        sent = v
        next_world = time.monotonic()
        while not closed.is_set():
            await changed.wait()
            changed.clear()
            if closed.is_set() or ws.application_state != WebSocketState.CONNECTED:
                break
            if st.params.version != params_version:
                params_version = st.params.version
                await send(dumps({"type": "params", "version": params_version,
                                          "values": st.params.values()}, "params"))
            v = st.views
            if v.geometry_seq != sent.geometry_seq and v.geometry is not None:
                await send(dumps({"type": "geometry", "geometry": v.geometry},
                                         "geometry"))
            if v.player_serial != sent.player_serial:
                await send(v.player_json)
            world_key = sent.world_key
            if v.world_key != sent.world_key:
                newest = v
                now = time.monotonic()
                if now < next_world:  # at most ws_max_hz: wait, then send the newest
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(closed.wait(), next_world - now)
                    if closed.is_set():
                        break
                    newest = st.views
                    if newest.serial != v.serial:
                        # what else changed while waiting (the player, geometry, health) is
                        # sent on the next turn: only the world is taken from the newest views
                        changed.set()
                next_world = max(next_world, now) + 1.0 / st.params.current.stream.ws_max_hz
                await send(newest.world_json)
                world_key = newest.world_key
            if v.health_mono != sent.health_mono:
                await send(v.health_json)
            sent = replace(v, world_key=world_key)
    finally:
        wakeups.discard(changed)
        rx.cancel()
