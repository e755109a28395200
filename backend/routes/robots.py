"""Operator targets: drive one robot to a point (the strategy drives it again when cleared)."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request

from .. import contract
from ..contract import TargetIn
from ..control.goto import Target
from ..messages import OperatorTarget
from ..station import Station
from .checks import IdParam, TeamParam, check_on_field, check_team
from .deps import OperatorDep, StationDep
from .operators import check_driving

router = APIRouter(prefix="/api/robots", tags=["robots"])


def _target(st: Station, target: OperatorTarget, action: str, who: str,
            details: dict[str, Any]) -> None:
    """On the station thread: onto the operator targets (the strategy takes them), and
    recorded."""
    st.operator_targets.write(target)
    st.operator_action(action, who, details)


@router.post("/{team}/{rid}/target")
async def set_target(team: TeamParam, rid: IdParam, body: TargetIn, st: StationDep,
                     caller: OperatorDep, request: Request) -> contract.TargetAnswer:
    check_team(st, team, rid)
    await check_driving(request, st, team)
    await check_on_field(st, body.x, body.y, "target")
    await st.call(_target, st, OperatorTarget(team, rid, Target(body.x, body.y,
                                                                  body.orientation)),
                  "target", caller.who, {"team": team, "id": rid, "x": body.x, "y": body.y,
                                         "orientation": body.orientation})
    return {"team": team, "id": rid,
            "target": {"x": body.x, "y": body.y, "orientation": body.orientation}}


@router.delete("/{team}/{rid}/target")
async def clear_target(team: TeamParam, rid: IdParam, st: StationDep,
                       caller: OperatorDep, request: Request) -> contract.TargetAnswer:
    await check_driving(request, st, team)
    await st.call(_target, st, OperatorTarget(team, rid, None), "clear-target", caller.who,
                  {"team": team, "id": rid})
    return {"team": team, "id": rid, "target": None}
