"""Operator targets: drive one robot to a point (the strategy drives it again when cleared)."""

from __future__ import annotations

from fastapi import APIRouter, Request

from .. import contract
from ..contract import TargetIn
from .checks import IdParam, TeamParam, check_on_field, check_team
from .deps import OperatorDep, StationDep
from .operators import check_driving

router = APIRouter(prefix="/api/robots", tags=["robots"])


@router.post("/{team}/{rid}/target")
async def set_target(team: TeamParam, rid: IdParam, body: TargetIn, st: StationDep,
                     caller: OperatorDep, request: Request) -> contract.TargetAnswer:
    check_team(st, team, rid)
    await check_driving(request, st, team)
    await check_on_field(st, body.x, body.y, "target")
    await st.call(st.set_target, team, rid, body.x, body.y, body.orientation)
    await st.call(st.operator_action, "target", caller.who,
                  {"team": team, "id": rid, "x": body.x, "y": body.y,
                   "orientation": body.orientation})
    return {"team": team, "id": rid,
            "target": {"x": body.x, "y": body.y, "orientation": body.orientation}}


@router.delete("/{team}/{rid}/target")
async def clear_target(team: TeamParam, rid: IdParam, st: StationDep,
                       caller: OperatorDep, request: Request) -> contract.TargetAnswer:
    await check_driving(request, st, team)
    await st.call(st.clear_target, team, rid)
    await st.call(st.operator_action, "clear-target", caller.who, {"team": team, "id": rid})
    return {"team": team, "id": rid, "target": None}
