"""The referee: what is obeyed, and the internal referee the operator drives."""

from __future__ import annotations

import logging

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from .. import contract
from ..contract import CardIn, EnableIn, RefereeCommandIn
from ..jsonsafe import SafeJSONResponse
from ..referee.internal import RefereeCommandError
from ..station import Station
from ..world.state import Team
from .checks import check_on_field
from .deps import VIEWER, OperatorDep, StationDep

log = logging.getLogger("touchline.api")

router = APIRouter(prefix="/api/referee", tags=["referee"])


def _foreign(st: Station) -> JSONResponse | None:
    other = st.internal_referee.foreign_active()
    if other is None:
        return None
    return JSONResponse(status_code=409, content={
        "detail": f"a game controller is active ({other}): the internal referee stays off"})


@router.get("", dependencies=[VIEWER])
async def referee_get(st: StationDep) -> JSONResponse:
    world = await st.read(st.browser.world)
    return SafeJSONResponse({**await st.call(st.browser.referee), "active": world["referee"]},
                            what="referee")


@router.post("/internal/enabled", response_model=None)
async def referee_enable(body: EnableIn, st: StationDep,
                         caller: OperatorDep) -> contract.RefereeView | JSONResponse:
    try:
        await st.call(st.internal_referee.enable, body.enabled)
    except RefereeCommandError as exc:
        return JSONResponse(status_code=409, content={"detail": str(exc)})
    await st.call(st.operator_action, "internal-referee", caller.who,
                  {"enabled": body.enabled})
    return await st.call(st.browser.referee)


@router.post("/internal/command", response_model=None)
async def referee_command(body: RefereeCommandIn, st: StationDep,
                          caller: OperatorDep) -> contract.RefereeView | JSONResponse:
    dp = body.designated_position
    if dp is not None:
        await check_on_field(st, dp.x, dp.y)
    refused = _foreign(st)
    if refused is not None:
        return refused
    try:
        await st.call(st.referee_state.give, body.command,
                      None if dp is None else (dp.x, dp.y))
    except RefereeCommandError as exc:
        return JSONResponse(status_code=422, content={"detail": [
            {"loc": ["body", "command"], "msg": str(exc), "type": "value_error"}]})
    await st.call(st.internal_referee.enable, True)
    await st.call(st.operator_action, "referee", caller.who,
                  {"command": body.command,
                   "designated_position": None if dp is None else {"x": dp.x, "y": dp.y}})
    log.info("internal referee: %s", body.command)
    return await st.call(st.browser.referee)


def _card(st: Station, team: Team, card: str) -> None:
    """On the station thread: a card from the internal referee (the division's robots per
    team follow the field: its processor keeps them)."""
    st.referee_state.card(team, card)


@router.post("/internal/card", response_model=None)
async def referee_card(body: CardIn, st: StationDep,
                       caller: OperatorDep) -> contract.RefereeView | JSONResponse:
    refused = _foreign(st)
    if refused is not None:
        return refused
    await st.call(_card, st, body.team, body.card)
    await st.call(st.internal_referee.enable, True)
    await st.call(st.operator_action, "card", caller.who,
                  {"team": body.team, "card": body.card})
    log.info("internal referee: %s card for %s", body.card, body.team)
    return await st.call(st.browser.referee)
