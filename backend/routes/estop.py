"""The emergency stop: pressed by one request, released only with a confirmation."""

from __future__ import annotations

import logging
from typing import Any

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from .. import contract
from ..access import estop_refusal
from ..contract import EstopIn
from ..estop import EstopState
from ..station import Station
from .deps import VIEWER, EstopDep, RuleDep, StationDep

log = logging.getLogger("touchline.api")

router = APIRouter(prefix="/api/estop", tags=["estop"])


@router.get("", dependencies=[VIEWER])
async def estop_get(st: StationDep) -> contract.EstopInfo:
    return await st.call(st.safety.estop_view)


@router.post("", response_model=None)
async def estop(body: EstopIn, st: StationDep, rule: RuleDep,
                caller: EstopDep) -> dict[str, Any] | JSONResponse:
    """Pressing is one request; a release must say ``confirm: true`` (the page asks the
    operator first) and is logged with who released it."""
    refused = estop_refusal(caller.role, rule, body.active)
    if refused is not None:
        return JSONResponse(status_code=403, content={"detail": refused})
    who = caller.who  # a viewer may press it (--estop-for-all)
    if not body.active and not body.confirm:
        return JSONResponse(status_code=409, content={"detail": (
            "releasing the emergency stop must be confirmed: send "
            '{"active": false, "confirm": true}')})
    was, view = await st.call(_set, st, body.active, who, body.reason)
    if body.active:
        log.warning("emergency stop ACTIVE: pressed by %s", who)
    else:
        log.warning("emergency stop RELEASED by %s (pressed by %s)%s", who, was.by,
                    f": {body.reason}" if body.reason else "")
    return {"estop": body.active, **view}


def _set(st: Station, active: bool, who: str,
         reason: str) -> tuple[EstopState, contract.EstopInfo]:
    """One press (or release) is one call on the station's queue: the stop set (latched,
    persisted, on the bus), the action recorded, the state answered."""
    was = st.safety.latch.state
    st.safety.set_estop(active, who)
    st.operator_action("estop" if active else "estop-release", who, {"reason": reason})
    return was, st.safety.estop_view()
