"""The log player (docs/api.md, "Replay and recording"): GET/POST /api/player,
GET /api/player/history, GET /api/logs."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import APIRouter, Query
from fastapi.responses import JSONResponse, Response

from .. import contract
from ..contract import PlayerIn
from ..filters.params import FilterSettings
from ..replay.history import history
from ..replay.logs import list_logs
from ..replay.player import LogSource, PlayerError
from .deps import OPERATOR, VIEWER, StationDep

router = APIRouter(prefix="/api", tags=["replay"])


def _answer(text: str) -> Response:
    # the player's JSON is made on the station thread, its events once per log (FastAPI's
    # encoder took 80 ms for a match's thousands of events)
    body = text[len('{"type":"player","player":'):-1]
    return Response(body, media_type="application/json")


@router.get("/player", response_model=contract.Player, dependencies=[VIEWER])
async def player_get(st: StationDep) -> Response:
    return _answer(await st.read(st.replay.player.json))


@router.post("/player", response_model=None, dependencies=[OPERATOR])
async def player_post(body: PlayerIn, st: StationDep) -> Response:
    """One action on the player; a refused one is answered with the reason: 422 for a
    value that can never work (a path outside the log folders, a speed out of range),
    409 for one that cannot now (no log open, nothing to jump to)."""
    p = st.replay.player
    try:
        if body.action == "open":
            await st.read(st.replay.open_log, body.path)
            return _answer(await st.read(st.replay.player.json))
        if body.action == "live":
            await st.call(st.replay.command, p.live)
        elif body.action == "play":
            await st.call(st.replay.command, p.play, body.speed)
        elif body.action == "pause":
            await st.call(st.replay.command, p.pause)
        elif body.action == "seek":
            await st.call(st.replay.command, p.seek, body.position_s)
        elif body.action == "step":
            await st.call(st.replay.command, p.step, body.frames)
        elif body.action == "jump":
            await st.call(st.replay.command, p.jump, body.kind, body.direction)
    except PlayerError as exc:
        status = 409 if p.log is None or body.action == "jump" else 422
        if body.action == "open":
            status = 422
        return JSONResponse(status_code=status, content={"detail": [
            {"loc": ["body", body.action], "msg": str(exc), "type": "player"}]})
    return _answer(await st.read(st.replay.player.json))


@router.get("/player/history", response_model=None, dependencies=[VIEWER])
async def player_history(
        st: StationDep,
        seconds: Annotated[float, Query(gt=0, le=300, allow_inf_nan=False,
                                        description="how far back, s")] = 30.0,
) -> contract.PlayerHistory | JSONResponse:
    """The plots' past after a seek, computed in a worker thread (not the station's)."""
    def where() -> tuple[LogSource | None, int, int, FilterSettings]:
        player = st.replay.player
        return (player.log, player.position_ns(), player.epoch,
                st.params.current.filters)
    log, end_ns, epoch, filters = await st.read(where)
    if log is None:
        return JSONResponse(status_code=409, content={"detail": "no log is open"})
    samples = await asyncio.to_thread(history, log, end_ns, seconds, filters)
    return {"epoch": epoch, "samples": samples}


@router.get("/logs", dependencies=[VIEWER])
async def logs(st: StationDep) -> contract.LogList:
    # the folders from the station, the scan in a worker thread (not the station's)
    folders = await st.read(st.replay.folders.folders)
    return await asyncio.to_thread(list_logs, folders)
