"""The Evaluate tab (docs/evaluate.md, docs/api.md "Evaluation"): GET /api/evaluate, POST
/api/evaluate (start or cancel a job), GET /api/evaluate/reports/{name} (and its page),
POST /api/evaluate/replay (a run's log in the player). Everything is named: no path from the
web (docs/security.md)."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import APIRouter, Path
from fastapi.responses import HTMLResponse, JSONResponse, Response

from .. import contract
from ..contract import EvaluateIn, EvaluateReplayIn, EvaluateStartIn
from ..evaluation import EvaluationError
from ..replay.player import PlayerError
from .deps import OPERATOR, VIEWER, OperatorDep, StationDep

router = APIRouter(prefix="/api/evaluate", tags=["evaluate"])

ReportName = Annotated[str, Path(pattern=r"^[A-Za-z0-9][A-Za-z0-9_.#-]{0,119}$")]


def _refused(exc: EvaluationError | PlayerError) -> JSONResponse:
    status = exc.status if isinstance(exc, EvaluationError) else 422
    return JSONResponse(status_code=status, content={"detail": str(exc)})


@router.get("", dependencies=[VIEWER])
async def evaluate_view(st: StationDep) -> contract.EvaluationView:
    """Suites (read from their folders in a worker thread), the job, the reports."""
    return await asyncio.to_thread(st.evaluation.view)


@router.post("", response_model=None)
async def evaluate_post(body: EvaluateIn, st: StationDep,
                        caller: OperatorDep) -> contract.EvaluationJob | JSONResponse:
    """Start a job (409 while one runs, 404 for an unknown suite) or cancel it."""
    ev = st.evaluation
    try:
        if isinstance(body, EvaluateStartIn):
            job = await asyncio.to_thread(ev.start, body.kind, body.suite, body.play,
                                          caller.who)
            st.operator_action("evaluate", caller.who, {"kind": body.kind, "suite": body.suite,
                                                        "play": body.play})
            return job
        return ev.cancel()
    except EvaluationError as exc:
        return _refused(exc)


@router.get("/reports/{name}", response_model=None, dependencies=[VIEWER])
async def evaluate_report(name: ReportName,
                          st: StationDep) -> contract.EvaluationReport | JSONResponse:
    try:
        return await asyncio.to_thread(st.evaluation.report, name)
    except EvaluationError as exc:
        return _refused(exc)


@router.get("/reports/{name}/html", response_model=None, dependencies=[VIEWER])
async def evaluate_report_html(name: ReportName, st: StationDep) -> Response:
    """The report's own page (self-contained: no script, nothing from elsewhere)."""
    try:
        page = await asyncio.to_thread(st.evaluation.report_html, name)
    except EvaluationError as exc:
        return _refused(exc)
    return HTMLResponse(page, headers={"Content-Security-Policy": "default-src 'none'; "
                                       "style-src 'unsafe-inline'; img-src data:"})


@router.post("/replay", response_model=None, dependencies=[OPERATOR])
async def evaluate_replay(body: EvaluateReplayIn,
                          st: StationDep) -> contract.Player | JSONResponse:
    """A run's SSL log in the player (the replay timeline), by report and run name."""
    try:
        # by names: the evaluation finds the log, inside the reports folder only
        real = await asyncio.to_thread(st.evaluation.run_log, body.report, body.run)
        return await st.read(st.replay.open_checked, real)
    except (EvaluationError, PlayerError) as exc:
        return _refused(exc)


