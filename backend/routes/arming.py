"""Arming: where the relay requires it, commands reach the robots only once armed."""

from __future__ import annotations

import logging

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from .. import contract
from ..contract import ArmIn
from .deps import VIEWER, OperatorDep, StationDep

log = logging.getLogger("touchline.api")

router = APIRouter(prefix="/api/arm", tags=["arming"])


@router.get("", dependencies=[VIEWER])
async def arm_get(st: StationDep) -> contract.ArmingInfo:
    return await st.call(st.arming_view)


@router.post("", response_model=None)
async def arm(body: ArmIn, st: StationDep,
              caller: OperatorDep) -> contract.ArmingInfo | JSONResponse:
    """Arms the station (real robots: commands reach them; refused with 409 and the
    reason while vision is missing, the e-stop is active or a log is replayed) or
    disarms it (always)."""
    refused = await st.call(st.set_armed, body.armed, caller.who)
    if refused is not None:
        log.warning("arming refused (%s): %s", caller.who, refused)
        return JSONResponse(status_code=409, content={"detail": refused})
    await st.call(st.operator_action, "arm" if body.armed else "disarm", caller.who, {})
    return await st.call(st.arming_view)
