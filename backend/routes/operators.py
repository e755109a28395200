"""Several operators (issue 12; the logic is backend/operators.py): who am I, who is connected,
driving (ask, give, take over, release), and the hooks the other routes call: ``check_driving``
(may this caller drive that team: 409 naming the holder if not), ``check_params`` (a play
change drives our team; a change made on an older parameter version is refused with the newer
value), ``set_name_cookie`` (``/login?name=``) and ``ws_session`` (each websocket client is a
session)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from typing import Any
from urllib.parse import quote

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import JSONResponse, Response
from starlette.requests import HTTPConnection

from ..contract import DrivingIn
from ..operators import DrivingRefused, clean_name
from ..station import Station
from .checks import TeamParam
from .deps import NAME_COOKIE, OperatorDep, StationDep, ViewerDep, who_of

#: the parameter version the page's change was made on (``?version=`` works too)
VERSION_HEADER = "x-touchline-params-version"

router = APIRouter(prefix="/api")


async def check_driving(request: HTTPConnection, st: Station, team: str) -> None:
    """Raises 409 (naming the holder) unless this caller drives ``team``; the first to drive a
    free team takes it (recorded)."""
    who = who_of(request)
    try:
        taken = st.operators.drive(who, team)
    except DrivingRefused as exc:
        raise HTTPException(409, str(exc)) from None
    if taken:
        await st.call(st.operator_action, "driving-taken", str(who), {"team": team})


async def check_params(request: Request, st: Station, body: Any) -> None:
    """Before a PATCH of the parameters: a play change drives our team (the lock); a change
    made on version N (``X-Touchline-Params-Version`` or ``?version=``) of leaves changed
    since is refused (409) with the value now."""
    raw = request.headers.get(VERSION_HEADER) or request.query_params.get("version")
    if raw is not None:
        try:
            seen = int(raw)
        except ValueError:
            raise HTTPException(422, [{"loc": ["header", VERSION_HEADER],
                                       "msg": f"not a version number: {raw[:20]!r}",
                                       "type": "int_parsing"}]) from None
        stale = st.params.changed_since(body, seen)
        if stale:
            raise HTTPException(409, [{
                "loc": ["body", *c["path"].split(".")],
                "msg": f"changed meanwhile to {c['to']!r} (version {st.params.version}); "
                       f"your {c['from']!r} was made on version {seen}: not applied",
                "type": "stale_version", "value_now": c["to"]} for c in stale])
    strategy = body.get("strategy") if isinstance(body, dict) else None
    if isinstance(strategy, dict) and "play" in strategy:
        await check_driving(request, st, st.params.current.team.our_team)


def set_name_cookie(answer: Response, raw: str) -> None:
    """``/login?name=``: the name goes with every request (readable by the page, which shows
    and may change it; not a secret)."""
    name = clean_name(raw)
    if name is not None:
        answer.set_cookie(NAME_COOKIE, quote(name), max_age=365 * 24 * 3600, path="/",
                          samesite="strict")


@contextlib.contextmanager
def ws_session(conn: HTTPConnection, st: Station) -> Iterator[None]:
    """A websocket client is a session (the Health tab lists them) while it is open."""
    sid = st.operators.connect(who_of(conn))
    try:
        yield
    finally:
        st.operators.disconnect(sid)


def _state(st: Station, request: Request) -> dict[str, Any]:
    ops = st.operators
    who = who_of(request)
    return {"me": {"key": who.key, "name": who.name, "role": who.role,
                   "address": who.address},
            "operators": ops.sessions(), "driving": ops.driving(),
            "actions": ops.actions()}


@router.get("/operators")
async def operators_get(request: Request, st: StationDep, _: ViewerDep) -> dict[str, Any]:
    """Who am I, who is connected, who drives which team, the latest actions."""
    return _state(st, request)


@router.post("/driving/{team}/request")
async def driving_request(team: TeamParam, request: Request, st: StationDep,
                          caller: OperatorDep) -> dict[str, Any]:
    """Ask the holder for driving (their page shows it with an accept); a free team is
    taken at once."""
    who = caller.operator
    holder = st.operators.request(who, team)
    if holder is None:
        await st.call(st.operator_action, "driving-taken", str(who), {"team": team})
    elif holder.key != who.key:
        await st.call(st.operator_action, "driving-requested", str(who),
                      {"team": team, "holder": holder.name})
    return _state(st, request)


@router.post("/driving/{team}/give")
async def driving_give(team: TeamParam, request: Request, st: StationDep,
                       caller: OperatorDep) -> dict[str, Any]:
    """The holder accepts the request: the one who asked drives now."""
    who = caller.operator
    try:
        to = st.operators.give(who, team)
    except ValueError as exc:
        raise HTTPException(409, str(exc)) from None
    await st.call(st.operator_action, "driving-given", str(who),
                  {"team": team, "to": to.name})
    return _state(st, request)


@router.post("/driving/{team}/take", response_model=None)
async def driving_take(team: TeamParam, body: DrivingIn, request: Request, st: StationDep,
                       caller: OperatorDep) -> dict[str, Any] | JSONResponse:
    """Take over driving from whoever holds it: must say ``confirm: true`` (the page asks
    first); recorded with both names."""
    who = caller.operator
    ops = st.operators
    holder = ops.holder(team)
    if holder is not None and holder.key != who.key and not body.confirm:
        return JSONResponse(status_code=409, content={"detail": (
            f"{team} is driven by {holder.name} ({holder.address}): taking over must be "
            'confirmed: send {"confirm": true}')})
    previous = ops.take_over(who, team)
    await st.call(st.operator_action, "driving-taken-over" if previous else "driving-taken",
                  str(who), {"team": team, "from": None if previous is None
                             else previous.name})
    return _state(st, request)


@router.post("/driving/{team}/release")
async def driving_release(team: TeamParam, request: Request, st: StationDep,
                          caller: OperatorDep) -> dict[str, Any]:
    who = caller.operator
    if not st.operators.release(who, team):
        raise HTTPException(409, f"{who.name} does not drive {team}: nothing to release")
    await st.call(st.operator_action, "driving-released", str(who), {"team": team})
    return _state(st, request)
