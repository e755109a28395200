"""Teleports through the simulator (SSL simulation protocol; grSim replacement in grsim mode).

They need the operator, not arming: a teleport only ever reaches a simulator. In robot-box
mode (real robots) it is refused here with 409, and the relay drops a SimulatorCommand there
too ("simulator commands unsupported in robot-box mode"), so nothing physical moves; an
external simulator's robots are moved by the simulator itself, and arming guards what the
robots are commanded to do, which a teleport does not change."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, Request

from sslpb import ssl_gc_common_pb2
from sslpb.ssl_simulation_control_pb2 import SimulatorCommand

from ..contract import TeleportBallIn, TeleportRobotIn
from ..station import Station
from ..world.state import Team
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


def ball_teleport(x_mm: float, y_mm: float, vx_mps: float = 0.0,
                  vy_mps: float = 0.0) -> bytes:
    """The SimulatorCommand (SSL simulation protocol, metres) that puts the ball there."""
    cmd = SimulatorCommand()
    b = cmd.control.teleport_ball
    b.x, b.y, b.z = x_mm / 1000.0, y_mm / 1000.0, 0.0
    b.vx, b.vy, b.vz = vx_mps, vy_mps, 0.0
    return cmd.SerializeToString()


def robot_teleport(team: Team, rid: int, x_mm: float, y_mm: float,
                   orientation: float | None, present: bool = True) -> bytes:
    """The SimulatorCommand that puts robot ``team``/``rid`` there, at rest."""
    cmd = SimulatorCommand()
    t = cmd.control.teleport_robot.add()
    t.id.id = rid
    t.id.team = ssl_gc_common_pb2.BLUE if team == "blue" else ssl_gc_common_pb2.YELLOW
    t.x, t.y = x_mm / 1000.0, y_mm / 1000.0
    if orientation is not None:
        t.orientation = orientation
    t.v_x = t.v_y = t.v_angular = 0.0
    t.present = present
    return cmd.SerializeToString()


def _send(st: Station, command: bytes, action: str, who: str, details: dict[str, Any]) -> None:
    """On the station thread: onto the simulator topic (the relay sends it), and recorded."""
    st.sim_commands.write(command)
    st.operator_action(action, who, details)


@router.post("/ball")
async def teleport_ball(body: TeleportBallIn, st: StationDep,
                        caller: OperatorDep) -> dict[str, Any]:
    check_simulator(st)
    await check_on_field(st, body.x, body.y)
    await st.call(_send, st, ball_teleport(body.x, body.y, body.vx, body.vy), "teleport-ball",
                  caller.who, body.model_dump())
    return {"ball": body.model_dump()}


@router.post("/robots/{team}/{rid}")
async def teleport_robot(team: TeamParam, rid: IdParam, body: TeleportRobotIn, st: StationDep,
                         caller: OperatorDep, request: Request) -> dict[str, Any]:
    check_simulator(st)
    await check_driving(request, st, team)
    await check_on_field(st, body.x, body.y)
    await st.call(_send, st, robot_teleport(team, rid, body.x, body.y, body.orientation,
                                            body.present),
                  "teleport-robot", caller.who, {"team": team, "id": rid, **body.model_dump()})
    return {"team": team, "id": rid, **body.model_dump()}
