"""Arming: where the relay requires it, commands reach the robots only once armed."""

from __future__ import annotations

import asyncio
import logging
import time

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from .. import contract
from ..contract import ArmIn
from .deps import VIEWER, OperatorDep, StationDep

log = logging.getLogger("touchline.api")

router = APIRouter(prefix="/api/arm", tags=["arming"])

#: how long the reply waits for the relay's statistics to show the change (it sends them at
#: once on a change, else every second)
CONFIRM_S = 2.0
_POLL_S = 0.02


@router.get("", dependencies=[VIEWER])
async def arm_get(st: StationDep) -> contract.ArmingInfo:
    return await st.call(st.safety.arming_view)


@router.post("", response_model=None)
async def arm(body: ArmIn, st: StationDep,
              caller: OperatorDep) -> contract.ArmingInfo | JSONResponse:
    """Arms the station (real robots: commands reach them; refused with 409 and the
    reason while vision is missing, the e-stop is active or a log is replayed) or
    disarms it (always)."""
    refused = await st.call(st.safety.set_armed, body.armed, caller.who)
    if refused is not None:
        log.warning("arming refused (%s): %s", caller.who, refused)
        return JSONResponse(status_code=409, content={"detail": refused})
    await st.call(st.operator_action, "arm" if body.armed else "disarm", caller.who, {})
    return await confirmed_view(st)


async def confirmed_view(st: StationDep, within_s: float = CONFIRM_S) -> contract.ArmingInfo:
    """The arming state once the relay's statistics show the station's state, or, while
    they do not, after ``within_s`` with ``relay_unconfirmed`` saying why. A relay without
    fresh statistics (down, never started) is not waited for: the reply says so at once."""
    deadline = time.monotonic() + within_s
    while True:
        doubt, alive = await st.read(st.safety.relay_arming_check)
        if doubt is None or not alive:
            return await st.read(st.safety.arming_view)
        if time.monotonic() >= deadline:
            view = await st.read(st.safety.arming_view)
            if view["relay_unconfirmed"] is not None:
                view["relay_unconfirmed"] = (
                    f"the relay has not confirmed within {within_s:g} s: "
                    f"{view['relay_unconfirmed']}; the station repeats its state to it every "
                    "0.5 s")
            return view
        await asyncio.sleep(_POLL_S)
