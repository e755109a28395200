"""Checks the driving routes share (targets, teleports, the referee's designated position):
each raises an HTTPException with the reason, in the 422 shape of a validation error."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import HTTPException
from fastapi import Path as PathParam

from ..station import Station
from ..world.state import Team

TeamParam = Annotated[Literal["blue", "yellow"], PathParam(description="robot team")]
IdParam = Annotated[int, PathParam(ge=0, le=15, description="robot id, 0..15")]


async def check_on_field(st: Station, x: float, y: float, what: str = "point") -> None:
    """A point within the field and its boundary (a 12 m x 9 m field before any geometry)."""
    geo = await st.read(st.browser.geometry)
    half_l = (geo["field_length"] / 2 + geo["boundary_width"]) if geo else 7000.0
    half_w = (geo["field_width"] / 2 + geo["boundary_width"]) if geo else 5000.0
    if abs(x) > half_l or abs(y) > half_w:
        raise HTTPException(422, [{
            "loc": ["body", "x" if abs(x) > half_l else "y"],
            "msg": f"{what} ({x:.0f}, {y:.0f}) mm is outside the field "
                   f"(|x| <= {half_l:.0f}, |y| <= {half_w:.0f})",
            "type": "outside_field"}])


def check_team(st: Station, team: Team, rid: int) -> None:
    why = st.safety.other_team_refusal(team, rid)
    if why is not None:
        raise HTTPException(422, [{"loc": ["path", "team"], "msg": why,
                                   "type": "other_team"}])
