"""The strategy as the station runs it (the play is chosen through the parameters)."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from ..jsonsafe import SafeJSONResponse
from .deps import VIEWER, StationDep

router = APIRouter(prefix="/api", tags=["strategy"])


@router.get("/strategy", dependencies=[VIEWER])
async def strategy_get(st: StationDep) -> JSONResponse:
    """The play, the plays to choose from (choose with PATCH /api/params
    {"strategy": {"play": name}}), the referee situation as our team sees it, roles."""
    return SafeJSONResponse(await st.call(st.browser.strategy), what="strategy")
