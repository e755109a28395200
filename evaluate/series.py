"""A series: what to run (a suite for one play, two plays on a suite, N matches of two plays,
the exercises for a class), run on a backend (``evaluate.pool``), summarised into the report's
data (``evaluate.report`` writes it as JSON and HTML).

The report's content depends only on the tasks and their results (in task order): the same
series with the same seeds gives the same report on the pool and on a cluster; only
``backend`` and ``timing`` differ.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from . import stats
from .pool import DaskCluster, LocalPool, Task
from .runner import Entrant, MatchTask, ScenarioTask
from .scenario import Suite

REPORT_VERSION = 1
Progress = Callable[[int, int, dict[str, Any]], None]


def safe_name(text: str) -> str:
    """A file or folder name from a label (letters, digits, ``_ . -``)."""
    s = re.sub(r"[^A-Za-z0-9_.-]+", "-", text).strip("-.")
    return s[:80] or "run"


def log_name(task_name: str) -> str:
    return safe_name(task_name.replace("#", "-")) + ".log"


def suite_tasks(suite: Suite, entrant: Entrant, runs_dir: Path | None,
                only: Sequence[str] = (), prefix: str = "") -> list[ScenarioTask]:
    tasks: list[ScenarioTask] = []
    for sc in suite.scenarios:
        if only and sc.name not in only:
            continue
        for i in range(sc.runs):
            t = ScenarioTask(sc, i, entrant, None, suite.checks_file)
            log = None if runs_dir is None else str(runs_dir / (prefix + log_name(t.name)))
            tasks.append(ScenarioTask(sc, i, entrant, log, suite.checks_file))
    return tasks


def match_tasks(a: Entrant, b: Entrant, matches: int, half_s: float, seed: int,
                runs_dir: Path | None, prefix: str = "", **kw: Any) -> list[MatchTask]:
    """``matches`` matches of ``a`` against ``b``: in each pair of matches the same seed, ``a``
    blue on the negative half, then yellow on the positive half (colours and sides swapped
    half the time); the seed changes from pair to pair."""
    tasks = []
    for i in range(matches):
        pair, swap = divmod(i, 2)
        blue, yellow = (b, a) if swap else (a, b)
        name = f"{prefix}match-{i + 1:03d}"
        log = None if runs_dir is None else str(runs_dir / f"{safe_name(name)}.log")
        tasks.append(MatchTask(name, blue, yellow, seed + pair, half_s,
                               blue_on_positive=bool(swap), log_path=log, **kw))
    return tasks


# -- summaries --------------------------------------------------------------------------------


def summarise_suite(results: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Per scenario (its runs: pass rate with its interval, mean score) and totals."""
    by: dict[str, list[dict[str, Any]]] = {}
    for r in results:
        by.setdefault(r["scenario"], []).append(r)
    scenarios = []
    for name, rs in by.items():
        k = sum(1 for r in rs if r.get("passed"))
        scores = [float(r.get("score") or 0.0) for r in rs]
        m, lo, hi = stats.mean_interval(scores)
        scenarios.append({
            "scenario": name, "title": rs[0].get("title", name), "runs": len(rs),
            "passed": k, "pass_rate": stats.rate(k, len(rs)), "score": round(m, 4),
            "score_low": round(lo, 4), "score_high": round(hi, 4),
            "errors": sum(1 for r in rs if r.get("error")),
            "failed_runs": [r["name"] for r in rs if not r.get("passed")]})
    n = len(results)
    k = sum(1 for r in results if r.get("passed"))
    scen_scores = [s["score"] for s in scenarios]
    return {"scenarios": scenarios, "totals": {
        "runs": n, "passed": k, "pass_rate": stats.rate(k, n),
        "scenarios": len(scenarios),
        "scenarios_passed": sum(1 for s in scenarios if s["passed"] == s["runs"]),
        "score": round(sum(scen_scores) / len(scen_scores), 4) if scen_scores else None,
        "errors": sum(1 for r in results if r.get("error"))}}


def _outcome(res: dict[str, Any], label: str) -> str | None:
    """"win" / "draw" / "loss" for the entrant ``label`` in a match result; None: no result."""
    if res.get("error") or "score" not in res:
        return None
    colour = "blue" if res["blue"] == label else "yellow" if res["yellow"] == label else None
    if colour is None:
        return None
    mine = res["score"][colour]
    theirs = res["score"]["yellow" if colour == "blue" else "blue"]
    return "win" if mine > theirs else "loss" if mine < theirs else "draw"


def summarise_matches(results: Sequence[dict[str, Any]], a: str, b: str) -> dict[str, Any]:
    """Wins, draws and losses of ``a`` against ``b``; the head-to-head verdict: ``a``'s share
    of the decided matches with Wilson's interval (0.5: as good as each other), and the
    difference of the two win rates among decided matches (2 p - 1) with that interval."""
    out = {"win": 0, "draw": 0, "loss": 0, "no_result": 0}
    gd: list[float] = []
    for r in results:
        o = _outcome(r, a)
        if o is None:
            out["no_result"] += 1
            continue
        out[o] += 1
        colour = "blue" if r["blue"] == a else "yellow"
        other = "yellow" if colour == "blue" else "blue"
        gd.append(float(r["score"][colour] - r["score"][other]))
    played = out["win"] + out["draw"] + out["loss"]
    decided = out["win"] + out["loss"]
    p, lo, hi = stats.wilson(out["win"], decided)
    m, mlo, mhi = stats.mean_interval(gd)
    if decided:
        d, dlo, dhi = 2 * p - 1, 2 * lo - 1, 2 * hi - 1
        verdict = stats.verdict(d, dlo, dhi, f"{a} minus {b} (win rates, decided matches)")
    else:
        d = dlo = dhi = math.nan
        verdict = "no decided match: nothing to compare"
    return {
        "a": a, "b": b, "played": played, **out,
        "win_rate": stats.rate(out["win"], played), "loss_rate": stats.rate(out["loss"], played),
        "draw_rate": stats.rate(out["draw"], played),
        "decided_share": stats.rate(out["win"], decided),
        "difference": {"difference": _r(d), "low": _r(dlo), "high": _r(dhi),
                       "significant": bool(decided) and (dlo > 0 or dhi < 0),
                       "verdict": verdict},
        "goal_difference": {"mean": _r(m), "low": _r(mlo), "high": _r(mhi)},
    }


def _r(v: float) -> float | None:
    return None if math.isnan(v) else round(v, 4)


def ab_suite(sa: dict[str, Any], sb: dict[str, Any], a: str, b: str) -> dict[str, Any]:
    """Two plays on the same suite: each pass rate and their difference (Newcombe)."""
    ta, tb = sa["totals"], sb["totals"]
    diff = stats.difference(ta["passed"], ta["runs"], tb["passed"], tb["runs"])
    diff["verdict"] = diff["verdict"].replace("the difference", f"{a} minus {b} (pass rates)")
    return {"a": a, "b": b, "a_pass_rate": ta["pass_rate"], "b_pass_rate": tb["pass_rate"],
            "difference": diff}


def ab_matches(ma: dict[str, Any], mb: dict[str, Any], a: str, b: str,
               opponent: str) -> dict[str, Any]:
    """Two plays each against the same opponent on the same seeds: each win rate and the
    difference (Newcombe)."""
    diff = stats.difference(ma["win"], ma["played"], mb["win"], mb["played"])
    diff["verdict"] = diff["verdict"].replace(
        "the difference", f"{a} minus {b} (win rates against {opponent})")
    return {"a": a, "b": b, "opponent": opponent, "a_win_rate": ma["win_rate"],
            "b_win_rate": mb["win_rate"], "difference": diff}


# -- running ----------------------------------------------------------------------------------


@dataclass
class Timing:
    wall_s: float
    run_wall_s: float  # the runs' own wall time added up
    sim_s: float
    runs: int

    def as_dict(self, workers: int) -> dict[str, Any]:
        per_core = self.runs / (self.run_wall_s / 60.0) if self.run_wall_s > 0 else None
        return {"wall_s": round(self.wall_s, 2), "run_wall_s": round(self.run_wall_s, 2),
                "sim_s": round(self.sim_s, 2), "runs": self.runs, "workers": workers,
                "runs_per_minute": round(self.runs / (self.wall_s / 60.0), 2)
                if self.wall_s > 0 else None,
                "runs_per_minute_per_worker": round(per_core, 2) if per_core else None,
                "speed_vs_real_time": round(self.sim_s / self.run_wall_s, 2)
                if self.run_wall_s > 0 else None}


def execute(backend: LocalPool | DaskCluster, tasks: Sequence[Task],
            progress: Progress | None = None,
            cancelled: Callable[[], bool] = lambda: False
            ) -> tuple[list[dict[str, Any]], Timing]:
    t0 = time.perf_counter()
    results = backend.run(tasks, progress, cancelled)
    wall = time.perf_counter() - t0
    return results, Timing(wall, sum(float(r.get("wall_s") or 0.0) for r in results),
                           sum(float(r.get("sim_s") or 0.0) for r in results), len(results))


def report_base(kind: str, title: str, backend: LocalPool | DaskCluster, timing: Timing,
                **extra: Any) -> dict[str, Any]:
    return {"version": REPORT_VERSION, "kind": kind, "title": title,
            "created_unix": round(time.time(), 3), "backend": backend.backend.as_dict(),
            "timing": timing.as_dict(backend.backend.workers), **extra}


def strip_volatile(report: dict[str, Any]) -> dict[str, Any]:
    """The report without what depends on where and when it ran (backend, timing, wall
    times, the creation time): what must be the same for the same seeds anywhere."""
    out = {k: v for k, v in report.items() if k not in ("backend", "timing", "created_unix")}
    if "runs" in out:
        out["runs"] = [{k: v for k, v in r.items() if k != "wall_s"} for r in out["runs"]]
    for key in ("a_runs", "b_runs"):
        if key in out:
            out[key] = [{k: v for k, v in r.items() if k != "wall_s"} for r in out[key]]
    return out
