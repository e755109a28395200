"""The series ``python -m evaluate`` and the station's Evaluate tab run: each builds its tasks,
runs them on a backend and writes the report (JSON + HTML) into its folder, the runs' logs in
``runs/`` beside it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from domain.wallclock import file_stamp

from .pool import DaskCluster, LocalPool
from .report import write_report
from .runner import Entrant
from .scenario import Suite, load_suite
from .series import (
    Progress,
    ab_matches,
    ab_suite,
    execute,
    match_tasks,
    report_base,
    safe_name,
    suite_tasks,
    summarise_matches,
    summarise_suite,
)

Backend = LocalPool | DaskCluster
RUNS = "runs"


def default_out(root: Path, what: str) -> Path:
    """``root/<date>-<time>-<what>`` (a new folder: a report is never overwritten)."""
    stamp = file_stamp()
    base = root / f"{stamp}-{safe_name(what)}"
    out, n = base, 1
    while out.exists():
        n += 1
        out = base.with_name(f"{base.name}-{n}")
    return out


def run_suite(suite: Suite, entrant: Entrant, out: Path, backend: Backend,
              progress: Progress | None = None, only: tuple[str, ...] = (),
              keep_logs: bool = True,
              cancelled: Callable[[], bool] = lambda: False) -> dict[str, Any]:
    tasks = suite_tasks(suite, entrant, out / RUNS if keep_logs else None, only)
    results, timing = execute(backend, tasks, progress, cancelled)
    rep = report_base("suite", f"{suite.name}: {entrant.name()}", backend, timing,
                      suite=suite.name, entrant=entrant.name(),
                      statements={s.name: {"title": s.title, "statement": s.statement}
                                  for s in suite.scenarios},
                      summary=summarise_suite(results), runs=results)
    write_report(out, rep)
    return rep


def run_ab_suite(suite: Suite, a: Entrant, b: Entrant, out: Path, backend: Backend,
                 progress: Progress | None = None, keep_logs: bool = True) -> dict[str, Any]:
    runs = out / RUNS if keep_logs else None
    ta = suite_tasks(suite, a, runs, prefix="A-")
    tb = suite_tasks(suite, b, runs, prefix="B-")
    results, timing = execute(backend, [*ta, *tb], progress)
    ra, rb = results[:len(ta)], results[len(ta):]
    sa, sb = summarise_suite(ra), summarise_suite(rb)
    rep = report_base("ab-suite", f"{suite.name}: A/B {a.name()} vs {b.name()}", backend,
                      timing, suite=suite.name, ab=ab_suite(sa, sb, a.name(), b.name()),
                      a_summary=sa, b_summary=sb, a_runs=ra, b_runs=rb)
    write_report(out, rep)
    return rep


def run_matches(a: Entrant, b: Entrant, matches: int, half_s: float, seed: int, out: Path,
                backend: Backend, progress: Progress | None = None, keep_logs: bool = True,
                **kw: Any) -> dict[str, Any]:
    tasks = match_tasks(a, b, matches, half_s, seed, out / RUNS if keep_logs else None, **kw)
    results, timing = execute(backend, tasks, progress)
    rep = report_base("matches", f"{a.name()} against {b.name()}: {matches} matches", backend,
                      timing, summary=summarise_matches(results, a.name(), b.name()),
                      runs=results, half_s=half_s, seed=seed)
    write_report(out, rep)
    return rep


def run_ab_matches(a: Entrant, b: Entrant, opponent: Entrant, matches: int, half_s: float,
                   seed: int, out: Path, backend: Backend, progress: Progress | None = None,
                   keep_logs: bool = True, **kw: Any) -> dict[str, Any]:
    runs = out / RUNS if keep_logs else None
    ta = match_tasks(a, opponent, matches, half_s, seed, runs, prefix="A-", **kw)
    tb = match_tasks(b, opponent, matches, half_s, seed, runs, prefix="B-", **kw)
    results, timing = execute(backend, [*ta, *tb], progress)
    ra, rb = results[:len(ta)], results[len(ta):]
    ma = summarise_matches(ra, a.name(), opponent.name())
    mb = summarise_matches(rb, b.name(), opponent.name())
    rep = report_base("ab-matches", f"A/B {a.name()} vs {b.name()} against {opponent.name()}",
                      backend, timing, ab=ab_matches(ma, mb, a.name(), b.name(),
                                                     opponent.name()),
                      a_summary=ma, b_summary=mb, a_runs=ra, b_runs=rb, half_s=half_s,
                      seed=seed)
    write_report(out, rep)
    return rep


def students_of(class_dir: Path) -> list[Path]:
    """The students' folders: each sub-folder (not hidden), by name."""
    return sorted(p for p in class_dir.iterdir() if p.is_dir() and not p.name.startswith("."))


def run_class(class_dir: Path, suite: Suite, out: Path, backend: Backend,
              progress: Progress | None = None, keep_logs: bool = True,
              params: dict[str, Any] | None = None,
              cancelled: Callable[[], bool] = lambda: False) -> dict[str, Any]:
    """The suite for every student (one sub-folder each: their team folder, the plays each
    scenario names in ``[ours] play``): the grade table student x exercise."""
    students = students_of(class_dir)
    if not students:
        raise ValueError(f"{class_dir}: no student folder in it")
    tasks = []
    owner: list[str] = []
    for st in students:
        ent = Entrant(None, params or {}, str(st), st.name)
        for t in suite_tasks(suite, ent, out / RUNS / safe_name(st.name) if keep_logs
                             else None):
            tasks.append(t)
            owner.append(st.name)
    results, timing = execute(backend, tasks, _with_student(progress, owner, tasks), cancelled)
    for r, who in zip(results, owner, strict=True):
        r["student"] = who
    exercises = [s.name for s in suite.scenarios]
    grades = []
    for st in students:
        rs = [r for r in results if r["student"] == st.name]
        summ = summarise_suite(rs)
        cells = {}
        for s in summ["scenarios"]:
            mine = [r for r in rs if r["scenario"] == s["scenario"]]
            first_fail = next((r for r in mine if not r.get("passed")), None)
            err = next((r.get("error") or r.get("team_error") for r in mine
                        if r.get("error") or r.get("team_error")), None)
            cells[s["scenario"]] = {
                "passed": s["passed"] == s["runs"], "score": s["score"],
                "runs": s["runs"], "runs_passed": s["passed"],
                "sim_s": round(sum(float(r.get("sim_s") or 0) for r in mine), 2),
                "replay": (first_fail or mine[0]).get("log"),
                "note": (str(err).splitlines()[0][:120] if err else
                         f"{s['passed']}/{s['runs']} runs" if s["runs"] > 1 else "")}
        tot = summ["totals"]
        grades.append({"student": st.name, "score": tot["score"] or 0.0,
                       "passed": tot["scenarios_passed"], "scenarios": tot["scenarios"],
                       "cells": cells})
    rep = report_base("class", f"class {class_dir.name}: {suite.name}", backend, timing,
                      suite=suite.name, exercises=exercises, grades=grades,
                      summary=summarise_suite(results), runs=results,
                      statements={s.name: {"title": s.title, "statement": s.statement}
                                  for s in suite.scenarios})
    write_report(out, rep)
    return rep


def _with_student(progress: Progress | None, owner: list[str],
                  tasks: list[Any]) -> Progress | None:
    """Progress that says whose run it was (results carry the task's log path)."""
    if progress is None:
        return None
    by_log = {t.log_path: who for t, who in zip(tasks, owner, strict=True) if t.log_path}

    def tell(done: int, total: int, res: dict[str, Any]) -> None:
        who = by_log.get(res.get("log"))
        progress(done, total, {**res, "student": who} if who else res)
    return tell


def load(name_or_path: str) -> Suite:
    return load_suite(name_or_path)


def with_params(e: Entrant, params: dict[str, Any]) -> Entrant:
    return replace(e, params={**dict(e.params), **params})
