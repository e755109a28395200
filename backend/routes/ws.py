"""The websocket ``/api/ws``: a snapshot, then every change of the station's published views.
The station notifies; nothing polls its state. After the snapshot a client of the station's
server is written by its loop's fan-out (``backend/wsfanout.py``); any other (a test client) is
served here through ASGI."""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable
from dataclasses import replace

from fastapi import APIRouter, WebSocket
from starlette.websockets import WebSocketDisconnect, WebSocketState

from sslnet.ratelog import RateLimitedLog

from ..jsonsafe import dumps
from ..station import Station
from ..viewhub import Views
from ..wsfanout import (
    STALLED_CLIENT_S,
    direct_socket,
    fanout_of,
    geometry_message,
    params_message,
)
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
    st.web.clients += 1
    try:
        async with ws_session(ws, st):
            await _serve_client(ws, st)
    except (WebSocketDisconnect, RuntimeError, ConnectionError):
        pass
    finally:
        st.web.clients -= 1


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
    except _Stalled:  # counted where it was found stalled (the fan-out, or a send here)
        peer = f"{ws.client.host}:{ws.client.port}" if ws.client else "?"
        _ws_log.warning("stalled", "websocket client %s took nothing for %.1f s: dropped "
                        "(%d so far)", peer, STALLED_CLIENT_S, st.web.dropped)


async def _serve_views(ws: WebSocket, st: Station) -> None:
    async def send(text: str) -> None:
        try:
            async with asyncio.timeout(STALLED_CLIENT_S):  # no task per send (wait_for makes one)
                await ws.send_text(text)
        except TimeoutError:
            st.web.dropped += 1
            raise _Stalled from None

    closed = asyncio.Event()
    changed = asyncio.Event()
    fanout = fanout_of(st)

    async def receive() -> None:
        try:
            while True:
                msg = await ws.receive()
                if msg["type"] == "websocket.disconnect":
                    break
        finally:
            closed.set()
            changed.set()

    sock = direct_socket(ws.scope)
    fanout.add(changed)  # publications from now on are not missed (and the views published)
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
        if sock is not None:  # from now on the fan-out writes every publication to it
            client = fanout.add_direct(sock, v, params_version, closed)
            fanout.discard(changed)
            try:
                await closed.wait()  # it closed, or the fan-out dropped it
            finally:
                fanout.discard_direct(client)
            if client.stalled:
                raise _Stalled
        else:
            await _serve_asgi(ws, st, send, v, params_version, closed, changed)
    finally:
        fanout.discard(changed)
        rx.cancel()


async def _serve_asgi(ws: WebSocket, st: Station, send: Callable[[str], Awaitable[None]],
                      sent: Views, params_version: int, closed: asyncio.Event,
                      changed: asyncio.Event) -> None:
    """Sends every change of the views through ASGI, woken by its loop's fan-out (a server
    whose connections cannot be written directly: the tests' client)."""
    next_world = time.monotonic()
    while not closed.is_set():
        await changed.wait()
        changed.clear()
        if closed.is_set() or ws.application_state != WebSocketState.CONNECTED:
            break
        if st.params.version != params_version:
            params_version = st.params.version
            await send(params_message(st))
        v = st.views
        if v.geometry_seq != sent.geometry_seq and v.geometry is not None:
            await send(geometry_message(v))
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
