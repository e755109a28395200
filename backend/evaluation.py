"""The Evaluate tab's side of the station: the suites it offers, one evaluation job at a time
(a suite for the station's play and parameters, or the class folder's students through the
exercises) run by ``evaluate`` in a process pool driven from a thread of its own (never the
station thread), its progress in every health message, the reports of the reports folder, and
a run's log opened in the player.

Nothing path-like comes from the web (docs/security.md, issue 30.1): suites, reports and runs
are named, and the names are looked up in the station's own folders (``--reports-dir``,
``--suite-dir``, ``--class-dir``, set at start); a run's log is opened only when its real path
is inside the reports folder.
"""

from __future__ import annotations

import logging
import math
import os
import re
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

# evaluate/ is imported inside the functions that use it: it is built on the backend (its
# headless runs are the station's own processors), so the backend may not import it at module
# level (tests/test_import_graph.py: no packages in a circle); and evaluate.jobs, .pool and
# .runner (the headless runner) stay out of the station's start, ordered for the first command
from . import contract
from .config import Settings
from .params.model import StationParams

log = logging.getLogger(__name__)

NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.#-]{0,119}$")
#: parameter groups a job takes from the station (the rest are the station's own business)
PARAM_GROUPS = ("strategy", "control", "filters", "world", "kicks", "safety", "processors")
MAX_REPORTS = 200
#: a job's pool workers run at this niceness: the station's own loop comes first
JOB_NICE = 10


class EvaluationError(ValueError):
    """A request the evaluation refuses (``status``: 404 no such thing, 409 not now, 422
    never)."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


def check_name(what: str, name: str) -> str:
    if not NAME.match(name) or ".." in name:
        raise EvaluationError(422, f"{what} {name!r}: a name of letters, digits, _ . # -")
    return name


def _flat_changes(changes: list[contract.ParamChange]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for c in changes:
        path = c["path"]
        if path.split(".")[0] in PARAM_GROUPS and path != "strategy.play":
            out[path] = c["to"]
    return out


class Evaluation:
    def __init__(self, settings: Settings, params: Callable[[], list[contract.ParamChange]],
                 current: Callable[[], StationParams],
                 workers: int | None = None) -> None:
        self.settings = settings
        self._changes = params
        self._current = current
        self.workers = workers or max(1, (os.cpu_count() or 2) - 1)
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._cancel = threading.Event()
        self._job: contract.EvaluationJob = _idle(0)

    # -- folders --------------------------------------------------------------------------

    @property
    def reports_folder(self) -> Path | None:
        return self.settings.reports_folder()

    def suites(self) -> dict[str, Path]:
        """Suite name -> folder: the shipped ones, then each ``--suite-dir`` folder's
        sub-folders with scenarios (a folder of scenarios itself counts too); the first of
        a name wins."""
        found: dict[str, Path] = {}
        from evaluate.scenario import SUITES_DIR

        roots = [SUITES_DIR, *self.settings.suite_dirs]
        for root in roots:
            if not root.is_dir():
                continue
            if any(root.glob("*.toml")) and root != SUITES_DIR:
                found.setdefault(root.name, root)
            for sub in sorted(root.iterdir()):
                if sub.is_dir() and any(sub.glob("*.toml")):
                    found.setdefault(sub.name, sub)
        return found

    def _suite(self, name: str) -> Any:  # an evaluate.scenario.Suite
        from evaluate.scenario import ScenarioError, load_suite

        folder = self.suites().get(check_name("suite", name))
        if folder is None:
            raise EvaluationError(404, f"no suite {name!r} (suites: "
                                       f"{', '.join(sorted(self.suites()))})")
        try:
            return load_suite(str(folder))
        except ScenarioError as exc:
            raise EvaluationError(422, str(exc)) from None

    def students(self) -> list[str]:
        from evaluate.jobs import students_of

        d = self.settings.class_dir
        if d is None or not d.is_dir():
            return []
        return [p.name for p in students_of(d)]

    # -- the view -------------------------------------------------------------------------

    def view(self) -> contract.EvaluationView:
        from evaluate.scenario import ScenarioError, load_suite

        suites: list[contract.EvaluationSuite] = []
        for name, folder in sorted(self.suites().items()):
            try:
                s = load_suite(str(folder))
            except ScenarioError as exc:
                suites.append({"name": name, "error": str(exc), "scenarios": []})
                continue
            suites.append({"name": name, "error": "", "scenarios": [
                {"name": sc.name, "title": sc.title, "statement": sc.statement,
                 "runs": sc.runs, "play": sc.play, "duration_s": sc.duration_s}
                for sc in s.scenarios]})
        reports = self.reports_folder
        return {
            "available": reports is not None,
            "reason": "" if reports is not None else
            "no reports folder: start the station with --reports-dir (or a state folder)",
            "suites": suites,
            "class_dir": None if self.settings.class_dir is None else str(self.settings.class_dir),
            "students": self.students(),
            "workers": self.workers,
            "cluster": self.settings.eval_cluster,
            "job": self.job(),
            "reports": self.reports(),
        }

    def job(self) -> contract.EvaluationJob:
        with self._lock:
            return dict(self._job)  # type: ignore[return-value]

    def reports(self) -> list[contract.EvaluationReportInfo]:
        from evaluate.report import REPORT_JSON, read_report

        folder = self.reports_folder
        if folder is None or not folder.is_dir():
            return []
        out: list[contract.EvaluationReportInfo] = []
        for sub in folder.iterdir():
            f = sub / REPORT_JSON
            if not NAME.match(sub.name) or not f.is_file():
                continue
            try:
                rep = read_report(sub)
            except (OSError, ValueError):
                continue
            out.append(_info(sub.name, rep))
        out.sort(key=lambda r: r["created_unix"], reverse=True)
        return out[:MAX_REPORTS]

    def _report_dir(self, name: str) -> Path:
        from evaluate.report import REPORT_JSON

        folder = self.reports_folder
        if folder is None:
            raise EvaluationError(409, "no reports folder")
        d = folder / check_name("report", name)
        if not (d / REPORT_JSON).is_file():
            raise EvaluationError(404, f"no report {name!r}")
        return d

    def report(self, name: str) -> contract.EvaluationReport:
        from evaluate.report import read_report

        d = self._report_dir(name)
        try:
            rep = read_report(d)
        except (OSError, ValueError) as exc:
            raise EvaluationError(422, f"report {name!r} cannot be read: {exc}") from None
        return _detail(name, rep)

    def report_html(self, name: str) -> bytes:
        from evaluate.report import REPORT_HTML

        d = self._report_dir(name)
        try:
            return (d / REPORT_HTML).read_bytes()
        except OSError as exc:
            raise EvaluationError(404, f"report {name!r} has no page: {exc}") from None

    def run_log(self, report: str, run: str) -> str:
        """The real path of a run's log, inside the reports folder."""
        from evaluate.report import read_report

        d = self._report_dir(report)
        check_name("run", run)
        rep = read_report(d)
        found = next((r for rid, r in _all_runs(rep) if rid == run), None)
        if found is None:
            raise EvaluationError(404, f"report {report!r} has no run {run!r}")
        path = found.get("log")
        if not path:
            raise EvaluationError(404, f"run {run!r} kept no log")
        real = Path(path).resolve()
        folder = self.reports_folder
        assert folder is not None
        if not real.is_relative_to(folder.resolve()) or real.suffix != ".log" \
                or not real.is_file():
            raise EvaluationError(404, f"run {run!r}: its log is not in the reports folder")
        return str(real)

    # -- jobs -----------------------------------------------------------------------------

    def start(self, kind: str, suite: str, play: str | None, by: str) -> contract.EvaluationJob:
        from evaluate.jobs import default_out

        folder = self.reports_folder
        if folder is None:
            raise EvaluationError(409, "no reports folder: start the station with "
                                       "--reports-dir")
        if play is not None:
            check_name("play", play)
        loaded = self._suite(suite)
        class_dir = self.settings.class_dir
        if kind == "class":
            if class_dir is None or not class_dir.is_dir():
                raise EvaluationError(409, "no class folder: start the station with "
                                           "--class-dir")
            if not self.students():
                raise EvaluationError(409, f"{class_dir}: no student folder in it")
        with self._lock:
            if self._job["state"] == "running":
                raise EvaluationError(409, f"a job runs ({self._job['suite']}, "
                                           f"{self._job['done']}/{self._job['total']}): wait "
                                           "for it or cancel it")
            job_id = self._job["id"] + 1
            out = default_out(folder, f"class-{loaded.name}" if kind == "class"
                              else loaded.name)
            total = sum(sc.runs for sc in loaded.scenarios) * (
                len(self.students()) if kind == "class" else 1)
            self._job = {**_idle(job_id), "state": "running", "kind": kind,  # type: ignore[typeddict-item]
                         "suite": loaded.name, "play": play, "total": total, "by": by,
                         "started_unix": time.time(), "report": out.name}
            self._cancel.clear()
        # the station's parameters as the operator tuned them (not its team and side: each
        # scenario says where our goal is); play None: each scenario's own
        params = _flat_changes(self._changes())
        self._thread = threading.Thread(
            target=self._run, name="evaluation-job",
            args=(kind, loaded, play, params, out), daemon=True)
        self._thread.start()
        return self.job()

    def cancel(self) -> contract.EvaluationJob:
        with self._lock:
            if self._job["state"] != "running":
                raise EvaluationError(409, "no job runs")
        self._cancel.set()
        return self.job()

    def _progress(self, done: int, total: int, res: dict[str, Any]) -> None:
        with self._lock:
            j = self._job
            j["done"], j["total"] = done, total
            if res.get("passed"):
                j["passed"] += 1
            else:
                j["failed"] += 1
            j["last"] = f"{res.get('student', '') + ' ' if res.get('student') else ''}" \
                        f"{res['name']}: {'passed' if res.get('passed') else 'failed'}"

    def _run(self, kind: str, suite: Any, play: str | None, params: dict[str, Any],
             out: Path) -> None:
        from evaluate.jobs import run_class, run_suite
        from evaluate.pool import DaskCluster, LocalPool
        from evaluate.runner import Entrant

        state, error = "done", ""
        pool: LocalPool | DaskCluster | None = None
        try:
            # a cluster (--eval-cluster) is connected to for each job: one that is down fails
            # that job with the reason, and the next job tries again
            pool = (DaskCluster(self.settings.eval_cluster) if self.settings.eval_cluster
                    else LocalPool(self.workers, nice=JOB_NICE))
            if kind == "class":
                assert self.settings.class_dir is not None
                run_class(self.settings.class_dir, suite, out, pool, self._progress,
                          params=params, cancelled=self._cancel.is_set)
            else:
                run_suite(suite, Entrant(play, params, self._team_dir()), out, pool,
                          self._progress, cancelled=self._cancel.is_set)
            if self._cancel.is_set():
                state = "cancelled"
        except Exception as exc:  # the job fails, the station goes on
            log.exception("evaluation job failed")
            state, error = "failed", f"{type(exc).__name__}: {exc}"
        finally:
            if pool is not None:
                pool.close()
        with self._lock:
            self._job["state"] = state  # type: ignore[typeddict-item]
            self._job["error"] = error
            self._job["finished_unix"] = time.time()

    def _team_dir(self) -> str | None:
        d = getattr(self.settings, "team_dir", None)
        return None if d is None else str(d)

    def close(self, timeout_s: float = 30.0) -> None:
        self._cancel.set()
        t = self._thread
        if t is not None:
            t.join(timeout_s)


def _idle(job_id: int) -> contract.EvaluationJob:
    return {"id": job_id, "state": "idle", "kind": None, "suite": "", "play": None, "done": 0,
            "total": 0, "passed": 0, "failed": 0, "started_unix": None, "finished_unix": None,
            "report": None, "by": "", "error": "", "last": ""}


def _run_id(r: dict[str, Any], side: str = "") -> str:
    """A run's name within its report: a class report's with the student's name first, an
    A/B's with its side (``A-``, ``B-``) unless its name has it (a match series' do)."""
    if r.get("student"):
        return f"{r['student']}.{r['name']}"
    name = str(r["name"])
    return f"{side}-{name}" if side and not name.startswith(f"{side}-") else name


def _all_runs(rep: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """Every run of a report with its id (an A/B suite runs each scenario once for A and
    once for B under the same name)."""
    return [(_run_id(r, side), r) for key, side in (("runs", ""), ("a_runs", "A"),
                                                     ("b_runs", "B"))
            for r in rep.get(key, [])]


def _team_error(r: dict[str, Any]) -> str:
    """A run's team play failure in one line: a scenario's ``team_error``, or a match's first
    (its result's ``team_errors`` by colour)."""
    te = r.get("team_error")
    result = r.get("result")
    by_colour = result.get("team_errors") if isinstance(result, dict) else None
    if not te and isinstance(by_colour, dict):
        te = next((f"{colour}: {errs[0]['why']}" for colour, errs in
                   sorted(by_colour.items()) if errs), "")
    return str(te).splitlines()[0] if te else ""


def _num(v: Any) -> float | None:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) \
        and math.isfinite(v) else None


def _info(name: str, rep: dict[str, Any]) -> contract.EvaluationReportInfo:
    runs = [r for k in ("runs", "a_runs", "b_runs") for r in rep.get(k, [])]
    summary = rep.get("summary", {})
    totals = summary.get("totals", {}) if isinstance(summary, dict) else {}
    return {"name": name, "title": str(rep.get("title", name)), "kind": str(rep.get("kind", "")),
            "created_unix": float(rep.get("created_unix") or 0.0), "runs": len(runs),
            "passed": sum(1 for r in runs if r.get("passed")),
            "score": _num(totals.get("score"))}


def _detail(name: str, rep: dict[str, Any]) -> contract.EvaluationReport:
    runs: list[contract.EvaluationRun] = []
    for rid, r in _all_runs(rep):
        detail = ""
        if r.get("kind") == "match" and isinstance(r.get("score"), dict):
            detail = f"{r['blue']} {r['score']['blue']} : {r['score']['yellow']} {r['yellow']}"
        err = r.get("error")
        runs.append({
            "id": rid, "name": str(r["name"]), "scenario": str(r.get("scenario", "")),
            "title": str(r.get("title", r["name"])), "student": r.get("student"),
            "seed": int(r.get("seed") or 0),
            "passed": bool(r.get("passed")), "score": _num(r.get("score")) or 0.0,
            "detail": detail, "error": str(err).splitlines()[0] if err else "",
            "team_error": _team_error(r),
            "sim_s": _num(r.get("sim_s")) or 0.0, "replay": bool(r.get("log")),
            "checks": [{"name": str(c["name"]), "label": str(c.get("label", c["name"])),
                        "passed": bool(c["passed"]), "score": float(c["score"]),
                        "detail": str(c["detail"])} for c in r.get("checks", [])]})
    grades: list[contract.EvaluationGrade] = []
    for g in rep.get("grades", []):
        cells: dict[str, contract.EvaluationCell] = {}
        for ex, c in g["cells"].items():
            run = None
            if c.get("replay"):
                hit = next((x for x in rep.get("runs", []) if x.get("log") == c["replay"]), None)
                run = _run_id(hit) if hit else None
            cells[ex] = {"passed": bool(c["passed"]), "score": float(c["score"]),
                         "runs": int(c["runs"]), "runs_passed": int(c["runs_passed"]),
                         "sim_s": float(c.get("sim_s") or 0.0), "note": str(c.get("note", "")),
                         "run": run}
        grades.append({"student": str(g["student"]), "score": float(g["score"]),
                       "passed": int(g["passed"]), "scenarios": int(g["scenarios"]),
                       "cells": cells})
    info = _info(name, rep)
    verdict = ""
    for key in ("ab", "summary"):
        d = rep.get(key)
        if isinstance(d, dict) and isinstance(d.get("difference"), dict):
            verdict = str(d["difference"].get("verdict", ""))
    return {**info, "verdict": verdict,
            "exercises": [str(x) for x in rep.get("exercises", [])], "grades": grades,
            "runs": runs, "timing": {k: v for k, v in rep.get("timing", {}).items()
                                     if isinstance(v, int | float) and not isinstance(v, bool)}}
