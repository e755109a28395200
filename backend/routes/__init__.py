"""The HTTP and websocket routes (docs/api.md), one router per resource; who may call each
route is its dependency (``deps``). ``backend.api.create_app`` assembles them."""

from __future__ import annotations

from fastapi import APIRouter

from . import (
    arming,
    estop,
    evaluate,
    login,
    operators,
    params,
    recording,
    referee,
    replay,
    robots,
    sim,
    strategy,
    team,
    token,
    views,
    ws,
)

#: every router, in the order the app includes them
ROUTERS: tuple[APIRouter, ...] = (
    views.router, ws.router, robots.router, sim.router, strategy.router, referee.router,
    estop.router, arming.router, params.router, replay.router, recording.router,
    token.router, login.router, operators.router, team.router, evaluate.router)
