"""Teleports through the simulator (SSL simulation protocol; grSim replacement in grsim mode).

They need the operator, not arming: a teleport only ever reaches a simulator. In robot-box
mode (real robots) it is refused here with 409, and the relay drops a SimulatorCommand there
too ("simulator commands unsupported in robot-box mode"), so nothing physical moves; an
external simulator's robots are moved by the simulator itself, and arming guards what the
robots are commanded to do, which a teleport does not change."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, Request

from ..contract import TeleportBallIn, TeleportRobotIn
from ..station import Station
from .checks import IdParam, TeamParam, check_on_field
from .deps import OperatorDep, StationDep
from .operators import check_driving

router = APIRouter(prefix="/api/sim", tags=["simulator"])


def check_simulator(st: Station) -> None:
    if st.replay.replaying:
        raise HTTPException(409, "replaying a log: nothing is sent to a simulator (go back "
                                 "to live first)")
    if st.safety.relay_output() == "robot-box":
        raise HTTPException(409, "no simulator: the relay drives real robots (robot-box), "
                                 "teleports need a simulator output")


@router.post("/ball")
async def teleport_ball(body: TeleportBallIn, st: StationDep,
                        caller: OperatorDep) -> dict[str, Any]:
    check_simulator(st)
    await check_on_field(st, body.x, body.y)
    await st.call(st.teleport_ball, body.x, body.y, body.vx, body.vy)
    await st.call(st.operator_action, "teleport-ball", caller.who, body.model_dump())
    return {"ball": body.model_dump()}


@router.post("/robots/{team}/{rid}")
async def teleport_robot(team: TeamParam, rid: IdParam, body: TeleportRobotIn, st: StationDep,
                         caller: OperatorDep, request: Request) -> dict[str, Any]:
    check_simulator(st)
    await check_driving(request, st, team)
    await check_on_field(st, body.x, body.y)
    await st.call(st.teleport_robot, team, rid, body.x, body.y, body.orientation,
                  body.present)
    await st.call(st.operator_action, "teleport-robot", caller.who,
                  {"team": team, "id": rid, **body.model_dump()})
    return {"team": team, "id": rid, **body.model_dump()}
