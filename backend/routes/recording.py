"""The recorder (docs/api.md, "Replay and recording"): POST /api/recording; its state comes
with every health message."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from .. import contract
from ..contract import RecordingIn
from .deps import OPERATOR, StationDep

router = APIRouter(prefix="/api", tags=["recording"])


@router.post("/recording", response_model=None, dependencies=[OPERATOR])
async def recording_post(body: RecordingIn,
                         st: StationDep) -> contract.Recording | JSONResponse:
    """A new file now, or recording on/off (the recording.enabled parameter)."""
    try:
        return await st.call(st.recording.command, body.action)
    except ValueError as exc:
        return JSONResponse(status_code=409, content={"detail": str(exc)})
