"""The HTTP and websocket API (docs/api.md) and the built frontend, on one port."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from collections.abc import AsyncIterator
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any, Literal

from fastapi import APIRouter, FastAPI, HTTPException, Request, WebSocket
from fastapi import Path as PathParam
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles
from starlette.websockets import WebSocketDisconnect, WebSocketState

from sslnet.ratelog import RateLimitedLog

from . import contract
from .access import (
    COOKIE,
    ROLE_KEY,
    AccessGuard,
    AccessRule,
    base_url,
    client_of,
    estop_refusal,
    print_login,
)
from .config import Settings
from .contract import (
    ArmIn,
    CardIn,
    EnableIn,
    EstopIn,
    RefereeCommandIn,
    TargetIn,
    TeleportBallIn,
    TeleportRobotIn,
)
from .jsonsafe import SafeJSONResponse, dumps
from .params.store import ParamError, PresetNotFound, diff, format_errors
from .referee.internal import RefereeCommandError
from .replay.routes import player_routes, recording_routes
from .routes_operators import (
    check_driving,
    check_params,
    operator_routes,
    set_name_cookie,
    who_of,
    ws_session,
)
from .security import EdgeGuard
from .station import Station
from .world.state import Team

log = logging.getLogger("touchline.api")
_ws_log = RateLimitedLog(log, interval_s=10.0)

TeamParam = Annotated[Literal["blue", "yellow"], PathParam(description="robot team")]
IdParam = Annotated[int, PathParam(ge=0, le=15, description="robot id, 0..15")]


def create_app(settings: Settings, station: Station | None = None,
               access: AccessRule | None = None) -> FastAPI:
    st = station or Station(settings)
    rule = access or AccessRule.from_settings(
        settings.host, settings.state_dir, settings.require_token, settings.view_token,
        settings.estop_for_all)

    @contextlib.asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        await asyncio.to_thread(st.start_thread)
        try:
            yield
        finally:
            await asyncio.to_thread(st.stop_thread)

    # every answer renders, whatever a value in it is (backend.jsonsafe): never a 500 for it
    app = FastAPI(title="Touchline", version="0.1.0", lifespan=lifespan,
                  default_response_class=SafeJSONResponse)
    app.state.station = st
    app.state.access = rule
    st.access_health = rule.health
    # who may do what (backend.access), behind the EdgeGuard (the last added runs first)
    app.add_middleware(AccessGuard, rule=rule)
    # host allowlist, Origin, cross-site requests and body limits, before any route
    app.add_middleware(EdgeGuard, bound_host=settings.host, allow_hosts=settings.allowed_hosts,
                       dev_origins=settings.allowed_origins)

    @app.exception_handler(RequestValidationError)
    async def validation_handler(_req: Request, exc: RequestValidationError) -> JSONResponse:
        # The default handler echoes the input, and a NaN input makes it fail with a 500.
        return SafeJSONResponse(status_code=422,
                                content={"detail": format_errors(exc.errors())})

    @app.exception_handler(ParamError)
    async def param_error_handler(_req: Request, exc: ParamError) -> JSONResponse:
        return SafeJSONResponse(status_code=422, content={"detail": exc.errors})

    @app.exception_handler(PresetNotFound)
    async def preset_not_found_handler(_req: Request, exc: PresetNotFound) -> JSONResponse:
        return SafeJSONResponse(status_code=404,
                                content={"detail": f"no preset named {exc.args[0]!r}"})

    api = APIRouter(prefix="/api")

    @api.get("/health")
    async def health() -> JSONResponse:
        # current, computed on the station thread (the websocket gets the published one)
        return SafeJSONResponse(await st.read(st.health), what="health")

    @api.get("/world")
    async def world() -> JSONResponse:
        # current, built on the station thread (the websocket gets the published one)
        return SafeJSONResponse(await st.read(st.world_dict), what="world")

    @api.get("/geometry")
    async def geometry() -> JSONResponse:
        geo = await st.read(st.geometry)
        if geo is None:
            raise HTTPException(404, "no geometry packet received yet")
        return SafeJSONResponse(geo, what="geometry")

    async def _check_on_field(x: float, y: float, what: str = "point") -> None:
        geo = await st.read(st.geometry)
        half_l = (geo["field_length"] / 2 + geo["boundary_width"]) if geo else 7000.0
        half_w = (geo["field_width"] / 2 + geo["boundary_width"]) if geo else 5000.0
        if abs(x) > half_l or abs(y) > half_w:
            raise HTTPException(422, [{
                "loc": ["body", "x" if abs(x) > half_l else "y"],
                "msg": f"{what} ({x:.0f}, {y:.0f}) mm is outside the field "
                       f"(|x| <= {half_l:.0f}, |y| <= {half_w:.0f})",
                "type": "outside_field"}])

    def _check_simulator() -> None:
        if st.player.log is not None:
            raise HTTPException(409, "replaying a log: nothing is sent to a simulator (go back "
                                     "to live first)")
        if st.relay_output() == "robot-box":
            raise HTTPException(409, "no simulator: the relay drives real robots (robot-box), "
                                     "teleports need a simulator output")

    def _check_team(team: Team, rid: int) -> None:
        why = st.other_team_refusal(team, rid)
        if why is not None:
            raise HTTPException(422, [{"loc": ["path", "team"], "msg": why,
                                       "type": "other_team"}])

    @api.post("/robots/{team}/{rid}/target")
    async def set_target(team: TeamParam, rid: IdParam, body: TargetIn,
                         request: Request) -> contract.TargetAnswer:
        _check_team(team, rid)
        await check_driving(request, st, team)
        await _check_on_field(body.x, body.y, "target")
        await st.call(st.set_target, team, rid, body.x, body.y, body.orientation)
        await st.call(st.operator_action, "target", _who(request),
                      {"team": team, "id": rid, "x": body.x, "y": body.y,
                       "orientation": body.orientation})
        return {"team": team, "id": rid,
                "target": {"x": body.x, "y": body.y, "orientation": body.orientation}}

    @api.delete("/robots/{team}/{rid}/target")
    async def clear_target(team: TeamParam, rid: IdParam,
                           request: Request) -> contract.TargetAnswer:
        await check_driving(request, st, team)
        await st.call(st.clear_target, team, rid)
        await st.call(st.operator_action, "clear-target", _who(request),
                      {"team": team, "id": rid})
        return {"team": team, "id": rid, "target": None}

    @api.post("/sim/ball")
    async def teleport_ball(body: TeleportBallIn, request: Request) -> dict[str, Any]:
        _check_simulator()
        await _check_on_field(body.x, body.y)
        await st.call(st.teleport_ball, body.x, body.y, body.vx, body.vy)
        await st.call(st.operator_action, "teleport-ball", _who(request),
                      body.model_dump())
        return {"ball": body.model_dump()}

    @api.post("/sim/robots/{team}/{rid}")
    async def teleport_robot(team: TeamParam, rid: IdParam,
                             body: TeleportRobotIn, request: Request) -> dict[str, Any]:
        _check_simulator()
        await check_driving(request, st, team)
        await _check_on_field(body.x, body.y)
        await st.call(st.teleport_robot, team, rid, body.x, body.y, body.orientation,
                      body.present)
        await st.call(st.operator_action, "teleport-robot", _who(request),
                      {"team": team, "id": rid, **body.model_dump()})
        return {"team": team, "id": rid, **body.model_dump()}

    @api.get("/strategy")
    async def strategy_get() -> JSONResponse:
        """The play, the plays to choose from (choose with PATCH /api/params
        {"strategy": {"play": name}}), the referee situation as our team sees it, roles."""
        return SafeJSONResponse(await st.call(st.strategy_view), what="strategy")

    @api.get("/referee")
    async def referee_get() -> JSONResponse:
        world = await st.read(st.world_dict)
        return SafeJSONResponse({**await st.call(st.referee_view), "active": world["referee"]},
                                what="referee")

    @api.post("/referee/internal/enabled", response_model=None)
    async def referee_enable(body: EnableIn,
                             request: Request) -> contract.RefereeView | JSONResponse:
        try:
            await st.call(st.internal_referee.enable, body.enabled)
        except RefereeCommandError as exc:
            return JSONResponse(status_code=409, content={"detail": str(exc)})
        await st.call(st.operator_action, "internal-referee", _who(request),
                      {"enabled": body.enabled})
        return await st.call(st.referee_view)

    @api.post("/referee/internal/command", response_model=None)
    async def referee_command(body: RefereeCommandIn,
                              request: Request) -> contract.RefereeView | JSONResponse:
        dp = body.designated_position
        if dp is not None:
            await _check_on_field(dp.x, dp.y)
        other = st.internal_referee.foreign_active()
        if other is not None:
            return JSONResponse(status_code=409, content={
                "detail": f"a game controller is active ({other}): the internal referee "
                          "stays off"})
        try:
            await st.call(st.referee_state.give, body.command,
                          None if dp is None else (dp.x, dp.y))
        except RefereeCommandError as exc:
            return JSONResponse(status_code=422, content={"detail": [
                {"loc": ["body", "command"], "msg": str(exc), "type": "value_error"}]})
        await st.call(st.internal_referee.enable, True)
        await st.call(st.operator_action, "referee", _who(request),
                      {"command": body.command,
                       "designated_position": None if dp is None else {"x": dp.x, "y": dp.y}})
        log.info("internal referee: %s", body.command)
        return await st.call(st.referee_view)

    @api.post("/referee/internal/card", response_model=None)
    async def referee_card(body: CardIn,
                           request: Request) -> contract.RefereeView | JSONResponse:
        other = st.internal_referee.foreign_active()
        if other is not None:
            return JSONResponse(status_code=409, content={
                "detail": f"a game controller is active ({other}): the internal referee "
                          "stays off"})
        await st.call(st.give_card, body.team, body.card)
        await st.call(st.internal_referee.enable, True)
        await st.call(st.operator_action, "card", _who(request),
                      {"team": body.team, "card": body.card})
        log.info("internal referee: %s card for %s", body.card, body.team)
        return await st.call(st.referee_view)

    @api.get("/estop")
    async def estop_get() -> contract.EstopInfo:
        return await st.call(st.estop_view)

    @api.post("/estop", response_model=None)
    async def estop(body: EstopIn, request: Request) -> dict[str, Any] | JSONResponse:
        """Pressing is one request; a release must say ``confirm: true`` (the page asks the
        operator first) and is logged with who released it."""
        role = request.scope.get(ROLE_KEY)  # None (not set by the guard): no operator
        refused = estop_refusal(role, rule, body.active)
        if refused is not None:
            return JSONResponse(status_code=403, content={"detail": refused})
        who = str(who_of(request))  # a viewer may press it (--estop-for-all); never locked
        if not body.active and not body.confirm:
            return JSONResponse(status_code=409, content={"detail": (
                "releasing the emergency stop must be confirmed: send "
                '{"active": false, "confirm": true}')})
        if body.active:
            await st.call(st.set_estop, True, who)
            log.warning("emergency stop ACTIVE: pressed by %s", who)
        else:
            was = st.estop_latch.state
            await st.call(st.set_estop, False, who)
            log.warning("emergency stop RELEASED by %s (pressed by %s)%s", who, was.by,
                        f": {body.reason}" if body.reason else "")
        await st.call(st.operator_action, "estop" if body.active else "estop-release",
                      who, {"reason": body.reason})
        return {"estop": body.active, **await st.call(st.estop_view)}

    @api.get("/arm")
    async def arm_get() -> contract.ArmingInfo:
        return await st.call(st.arming_view)

    @api.post("/arm", response_model=None)
    async def arm(body: ArmIn, request: Request) -> contract.ArmingInfo | JSONResponse:
        """Arms the station (real robots: commands reach them; refused with 409 and the
        reason while vision is missing, the e-stop is active or a log is replayed) or
        disarms it (always)."""
        who = _who(request)
        refused = await st.call(st.set_armed, body.armed, who)
        if refused is not None:
            log.warning("arming refused (%s): %s", who, refused)
            return JSONResponse(status_code=409, content={"detail": refused})
        await st.call(st.operator_action, "arm" if body.armed else "disarm", who, {})
        return await st.call(st.arming_view)

    @api.websocket("/ws")
    async def ws_endpoint(ws: WebSocket) -> None:
        # Host and Origin were checked by the EdgeGuard before this runs
        await ws.accept()
        st.ws_clients += 1
        try:
            with ws_session(ws, st):
                await _serve_client(ws, st)
        except (WebSocketDisconnect, RuntimeError, ConnectionError):
            pass
        finally:
            st.ws_clients -= 1

    @api.post("/token/rotate")
    async def token_rotate(request: Request) -> JSONResponse:
        """A new operator token (the operator's only: the AccessGuard checked the current
        one), written and printed; every cookie and script holding the old one is refused."""
        try:
            token = rule.operator.rotate()
        except ValueError as exc:
            return JSONResponse(status_code=409, content={"detail": str(exc)})
        base = base_url(settings.host, settings.port, settings.allowed_hosts)
        print_login(rule, base)
        log.warning("operator token rotated by %s", _who(request))
        answer = JSONResponse({"rotated": True, "login_url": f"{base}/login?token={token}"})
        _set_cookie(answer, token)
        return answer

    @app.get("/login", response_model=None)
    async def login(request: Request, token: str = "",
                    name: str = "") -> JSONResponse | RedirectResponse:
        """Opened once per laptop with the URL printed at start: sets the cookie that goes
        with every request and the websocket, and opens the page. ``name``: the operator's
        name the others see (else the page asks for one)."""
        client = client_of(request.scope)
        left = rule.limiter.blocked(client)
        if left > 0:
            return JSONResponse(status_code=429, content={
                "detail": f"too many wrong tokens from {client}: try again in {left:.0f} s"})
        if not token or rule.role_of(token) is None:
            if token:
                rule.failed(client, token, "/login")
            return JSONResponse(status_code=401, content={"detail": (
                "wrong or missing token: open the URL printed when the station started "
                "(http://HOST:PORT/login?token=...)")})
        answer = RedirectResponse("/", status_code=303)
        _set_cookie(answer, token)
        set_name_cookie(answer, name)
        return answer

    _params_routes(api, st)
    player_routes(api, st)
    recording_routes(api, st)
    app.include_router(api)
    app.include_router(operator_routes(st))
    _mount_frontend(app, settings.static_dir)
    return app


def _set_cookie(answer: JSONResponse | RedirectResponse, token: str) -> None:
    # HttpOnly: no script reads it; SameSite=Strict: no other site's request carries it
    answer.set_cookie(COOKIE, token, max_age=30 * 24 * 3600, path="/", httponly=True,
                      samesite="strict")


def _who(request: Request) -> str:
    """Who did it, for the session log and the action list: name, role and address."""
    return str(who_of(request))


async def _json_body(request: Request) -> Any:
    try:
        return json.loads(await request.body())
    except RecursionError:  # the EdgeGuard refuses deep JSON first; a last line of defence
        raise ParamError([{"loc": ["body"], "msg": "JSON nested too deeply",
                           "type": "json_invalid"}]) from None
    except ValueError as exc:
        raise ParamError([{"loc": ["body"], "msg": f"invalid JSON: {exc}",
                           "type": "json_invalid"}]) from None


def _params_routes(api: APIRouter, st: Station) -> None:
    """Parameter and preset routes. A refused change raises ParamError (422 with field and
    reason) and a missing preset PresetNotFound (404), both answered by the app's handlers."""
    store = st.params

    async def _applied() -> contract.ParamsState:
        await st.call(lambda: None)  # the station loop has applied it before we answer
        return {"version": store.version, "values": store.values()}

    @api.get("/params/schema")
    async def params_schema() -> dict[str, Any]:
        return store.schema()

    @api.get("/params")
    async def params_get() -> contract.ParamsState:
        return {"version": store.version, "values": store.values()}

    @api.patch("/params")
    async def params_patch(request: Request) -> contract.ParamsState:
        body = await _json_body(request)
        await check_params(request, st, body)
        store.patch(body)
        strategy = body.get("strategy") if isinstance(body, dict) else None
        play = isinstance(strategy, dict) and "play" in strategy
        await st.call(st.operator_action, "play" if play else "params", _who(request),
                      {"changes": body})
        log.info("parameters changed to version %d", store.version)
        return await _applied()

    @api.get("/params/diff")
    async def params_diff() -> contract.ParamsDiff:
        return {"version": store.version, "changes": store.diff_from_defaults()}

    @api.get("/params/export")
    async def params_export() -> JSONResponse:
        return JSONResponse({"touchline_params": 1, "values": store.values()}, headers={
            "content-disposition": 'attachment; filename="touchline-params.json"'})

    @api.post("/params/import")
    async def params_import(request: Request) -> contract.ParamsState:
        body = await _json_body(request)
        store.replace(body["values"] if isinstance(body, dict) and "values" in body else body)
        await st.call(st.operator_action, "params-import", _who(request), {})
        return await _applied()

    @api.get("/presets")
    async def presets_list() -> contract.PresetList:
        return {"presets": store.list_presets()}

    @api.put("/presets/{name}")
    async def preset_save(name: str) -> contract.PresetList:
        store.save_preset(name)
        return {"presets": store.list_presets()}

    @api.get("/presets/{name}")
    async def preset_get(name: str) -> contract.PresetDetail:
        values = store.read_preset(name)
        return {"name": name, "values": values,
                "diff_from_defaults": diff(store.defaults.model_dump(mode="json"), values),
                "diff_from_current": diff(store.values(), values)}

    @api.post("/presets/{name}/load")
    async def preset_load(name: str, request: Request) -> contract.ParamsState:
        store.load_preset(name)
        await st.call(st.operator_action, "preset-load", _who(request), {"preset": name})
        return await _applied()

    @api.delete("/presets/{name}")
    async def preset_delete(name: str) -> contract.PresetList:
        store.delete_preset(name)
        return {"presets": store.list_presets()}


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


async def _serve_views(ws: WebSocket, st: Station) -> None:
    async def send(text: str) -> None:
        try:
            await asyncio.wait_for(ws.send_text(text), STALLED_CLIENT_S)
        except TimeoutError:
            raise _Stalled from None

    closed = asyncio.Event()
    changed = asyncio.Event()
    loop = asyncio.get_running_loop()
    def notify() -> None:  # on the station thread: only hand over to this client's loop
        loop.call_soon_threadsafe(changed.set)
    unsubscribe = st.subscribe_views(notify)

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
        unsubscribe()
        rx.cancel()


def _mount_frontend(app: FastAPI, static_dir: Path) -> None:
    if (static_dir / "index.html").exists():
        app.mount("/", StaticFiles(directory=static_dir, html=True), name="frontend")
        return

    @app.get("/", response_class=HTMLResponse)
    async def not_built() -> str:
        return ("<!doctype html><title>Touchline</title><h1>Touchline backend is running</h1>"
                f"<p>The frontend is not built ({static_dir} has no index.html). "
                "Run <code>make run</code>, which builds it.</p>")
