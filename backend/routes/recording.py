"""The recorder (docs/api.md, "Replay and recording"): POST /api/recording; its state comes
with every health message."""

from __future__ import annotations

import asyncio
import time

from fastapi import APIRouter
from fastapi.responses import JSONResponse

from .. import contract
from ..contract import RecordingIn
from .deps import OPERATOR, StationDep

router = APIRouter(prefix="/api", tags=["recording"])

#: how long a "new file" answer waits for the recorder's thread to open it
NEW_FILE_WAIT_S = 2.0


@router.post("/recording", response_model=None, dependencies=[OPERATOR])
async def recording_post(body: RecordingIn,
                         st: StationDep) -> contract.Recording | JSONResponse:
    """A new file now, or recording on/off (the recording.enabled parameter). A new file
    is answered once the recorder's thread has opened it (the answer names the new file,
    not the one just closed), or after NEW_FILE_WAIT_S with the state then."""
    try:
        if body.action != "new-file":
            return await st.call(st.recording.command, body.action)
        before = (await st.read(st.recording.status))["file"]
        answer = await st.call(st.recording.command, body.action)
    except ValueError as exc:
        return JSONResponse(status_code=409, content={"detail": str(exc)})
    deadline = time.monotonic() + NEW_FILE_WAIT_S
    while answer["file"] in ("", before) and time.monotonic() < deadline:
        await asyncio.sleep(0.02)
        answer = await st.read(st.recording.status)
    return answer
