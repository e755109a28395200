"""Several operators (issue 12; the logic is backend/operators.py): who am I, who is connected,
driving (ask, give, take over, release), and the hooks the other routes call: ``check_driving``
(may this caller drive that team: 409 naming the holder if not), ``check_params`` (a play
change drives our team; a change made on an older parameter version is refused with the newer
value), ``set_name_cookie`` (``/login?name=``) and ``ws_session`` (each websocket client is a
session). ``Operators`` is station state: every change and read of it here is one call on the
station's queue (the station thread is its one writer)."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from typing import Any
from urllib.parse import quote

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import JSONResponse, Response
from starlette.requests import HTTPConnection

from ..contract import DrivingIn
from ..operators import DrivingRefused, Who, clean_name
from ..station import Station
from .checks import TeamParam
from .deps import NAME_COOKIE, OperatorDep, StationDep, ViewerDep, who_of

#: the parameter version the page's change was made on (``?version=`` works too)
VERSION_HEADER = "x-touchline-params-version"

router = APIRouter(prefix="/api")


def drive_or_refuse(st: Station, who: Who, team: str) -> None:
    """On the station thread (Operators' one writer): raises 409 (naming the holder) unless
    ``who`` drives ``team``; the first to drive a free team takes it (recorded)."""
    try:
        taken = st.operators.drive(who, team)
    except DrivingRefused as exc:
        raise HTTPException(409, str(exc)) from None
    if taken:
        st.operator_action("driving-taken", str(who), {"team": team})


async def check_driving(request: HTTPConnection, st: Station, team: str) -> None:
    """``drive_or_refuse`` for this caller, as one call on the station's queue."""
    await st.call(drive_or_refuse, st, who_of(request), team)


def version_seen(request: Request) -> int | None:
    """The parameter version the caller's change was made on (``X-Touchline-Params-Version``
    or ``?version=``), None if not said; 422 if it is not a number."""
    raw = request.headers.get(VERSION_HEADER) or request.query_params.get("version")
    if raw is None:
        return None
    try:
        return int(raw)
    except ValueError:
        raise HTTPException(422, [{"loc": ["header", VERSION_HEADER],
                                   "msg": f"not a version number: {raw[:20]!r}",
                                   "type": "int_parsing"}]) from None


def check_params(st: Station, body: Any, seen: int | None, who: Who) -> None:
    """On the station thread, before a PATCH of the parameters: a change made on version
    ``seen`` of leaves changed since is refused (409) with the value now; a play change
    drives our team (the lock)."""
    if seen is not None:
        stale = st.params.changed_since(body, seen)
        if stale:
            raise HTTPException(409, [{
                "loc": ["body", *c["path"].split(".")],
                "msg": f"changed meanwhile to {c['to']!r} (version {st.params.version}); "
                       f"your {c['from']!r} was made on version {seen}: not applied",
                "type": "stale_version", "value_now": c["to"]} for c in stale])
    strategy = body.get("strategy") if isinstance(body, dict) else None
    if isinstance(strategy, dict) and "play" in strategy:
        drive_or_refuse(st, who, st.params.current.team.our_team)


def set_name_cookie(answer: Response, raw: str) -> None:
    """``/login?name=``: the name goes with every request (readable by the page, which shows
    and may change it; not a secret)."""
    name = clean_name(raw)
    if name is not None:
        answer.set_cookie(NAME_COOKIE, quote(name), max_age=365 * 24 * 3600, path="/",
                          samesite="strict")


@contextlib.asynccontextmanager
async def ws_session(conn: HTTPConnection, st: Station) -> AsyncIterator[None]:
    """A websocket client is a session (the Health tab lists them) while it is open; both
    ends are calls on the station's queue (Operators' one writer)."""
    sid = await st.call(st.operators.connect, who_of(conn))
    try:
        yield
    finally:
        await st.call(st.operators.disconnect, sid)


def _state(st: Station, me: Who) -> dict[str, Any]:
    """Who am I and the operators' state, read on the station thread."""
    ops = st.operators
    return {"me": {"key": me.key, "name": me.name, "role": me.role,
                   "address": me.address},
            "operators": ops.sessions(), "driving": ops.driving(),
            "actions": ops.actions()}


@router.get("/operators")
async def operators_get(request: Request, st: StationDep, _: ViewerDep) -> dict[str, Any]:
    """Who am I, who is connected, who drives which team, the latest actions."""
    return await st.read(_state, st, who_of(request))


def _request(st: Station, who: Who, me: Who, team: str) -> dict[str, Any]:
    holder = st.operators.request(who, team)
    if holder is None:
        st.operator_action("driving-taken", str(who), {"team": team})
    elif holder.key != who.key:
        st.operator_action("driving-requested", str(who), {"team": team, "holder": holder.name})
    return _state(st, me)


@router.post("/driving/{team}/request")
async def driving_request(team: TeamParam, request: Request, st: StationDep,
                          caller: OperatorDep) -> dict[str, Any]:
    """Ask the holder for driving (their page shows it with an accept); a free team is
    taken at once."""
    return await st.call(_request, st, caller.operator, who_of(request), team)


def _give(st: Station, who: Who, me: Who, team: str) -> dict[str, Any]:
    try:
        to = st.operators.give(who, team)
    except ValueError as exc:
        raise HTTPException(409, str(exc)) from None
    st.operator_action("driving-given", str(who), {"team": team, "to": to.name})
    return _state(st, me)


@router.post("/driving/{team}/give")
async def driving_give(team: TeamParam, request: Request, st: StationDep,
                       caller: OperatorDep) -> dict[str, Any]:
    """The holder accepts the request: the one who asked drives now."""
    return await st.call(_give, st, caller.operator, who_of(request), team)


def _take(st: Station, who: Who, me: Who, team: str,
          confirmed: bool) -> dict[str, Any] | JSONResponse:
    ops = st.operators
    holder = ops.holder(team)
    if holder is not None and holder.key != who.key and not confirmed:
        return JSONResponse(status_code=409, content={"detail": (
            f"{team} is driven by {holder.name} ({holder.address}): taking over must be "
            'confirmed: send {"confirm": true}')})
    previous = ops.take_over(who, team)
    st.operator_action("driving-taken-over" if previous else "driving-taken", str(who),
                       {"team": team, "from": None if previous is None else previous.name})
    return _state(st, me)


@router.post("/driving/{team}/take", response_model=None)
async def driving_take(team: TeamParam, body: DrivingIn, request: Request, st: StationDep,
                       caller: OperatorDep) -> dict[str, Any] | JSONResponse:
    """Take over driving from whoever holds it: must say ``confirm: true`` (the page asks
    first); recorded with both names."""
    return await st.call(_take, st, caller.operator, who_of(request), team, body.confirm)


def _release(st: Station, who: Who, me: Who, team: str) -> dict[str, Any]:
    if not st.operators.release(who, team):
        raise HTTPException(409, f"{who.name} does not drive {team}: nothing to release")
    st.operator_action("driving-released", str(who), {"team": team})
    return _state(st, me)


@router.post("/driving/{team}/release")
async def driving_release(team: TeamParam, request: Request, st: StationDep,
                          caller: OperatorDep) -> dict[str, Any]:
    return await st.call(_release, st, caller.operator, who_of(request), team)
