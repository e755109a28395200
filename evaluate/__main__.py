"""``python -m evaluate``: scenario suites, A/B comparisons, match series and class grades,
on the local process pool or a Dask cluster (docs/evaluate.md).

    python -m evaluate suite exercises --play match
    python -m evaluate ab regression --a match --b match --b-param strategy.kick_speed_mps=4
    python -m evaluate matches --a match --b simple --matches 40 --half-s 60
    python -m evaluate matches --a match --b match --b-param ... --opponent simple
    python -m evaluate class path/to/class --suite exercises
    python -m evaluate list
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

from .jobs import (
    default_out,
    run_ab_matches,
    run_ab_suite,
    run_class,
    run_matches,
    run_suite,
)
from .pool import DEFAULT_MEMORY_MB, make_backend
from .runner import Entrant
from .scenario import ScenarioError, load_suite, shipped_suites

ROOT = Path(__file__).resolve().parent.parent
REPORTS = ROOT / "var" / "reports"


def say(text: str, err: bool = False) -> None:
    stream = sys.stderr if err else sys.stdout
    stream.write(text + "\n")
    stream.flush()


def _param(item: str) -> tuple[str, Any]:
    key, sep, raw = item.partition("=")
    if not sep or not key.strip():
        raise argparse.ArgumentTypeError(f"expected group.key=value, got {item!r}")
    try:
        value: Any = json.loads(raw)
    except ValueError:
        value = raw
    return key.strip(), value


def _backend_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", type=_user_path, help="the report's folder (default: var/reports/"
                   "<date>-<time>-<what>)")
    p.add_argument("--workers", type=int, default=None,
                   help="local pool workers (default: one per core)")
    p.add_argument("--cluster", default=None, metavar="ADDRESS",
                   help="run on a Dask cluster: tcp://host:8786 (a running scheduler) or "
                        "local:N (a LocalCluster of N workers started here)")
    p.add_argument("--memory-mb", type=int, default=DEFAULT_MEMORY_MB,
                   help="memory limit of each worker (MB; 0: none)")
    p.add_argument("--no-logs", action="store_true", help="keep no SSL log of the runs")
    p.add_argument("--team-dir", type=os.path.expanduser, default=None,
                   help="the team folder team plays come from")


def _user_path(text: str) -> Path:
    """A folder with ``~`` expanded (zsh leaves the ``~`` of ``make evaluate TEAM=~/x``)."""
    return Path(text).expanduser()


def _entrant(play: str | None, params: list[tuple[str, Any]], team_dir: str | None,
             label: str = "") -> Entrant:
    return Entrant(play, dict(params), team_dir, label)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m evaluate", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("suite", help="a suite of scenarios for one play")
    s.add_argument("suite", help=f"a shipped suite ({', '.join(shipped_suites())}) or a folder")
    s.add_argument("--play", default=None, help="the play (default: each scenario's own)")
    s.add_argument("--param", action="append", type=_param, default=[], metavar="K=V")
    s.add_argument("--only", action="append", default=[], metavar="SCENARIO",
                   help="only this scenario (its name as `list` shows it; repeatable)")
    _backend_args(s)
    a = sub.add_parser("ab", help="two plays (or parameter sets) on one suite")
    a.add_argument("suite")
    for side in ("a", "b"):
        a.add_argument(f"--{side}", required=True, help=f"play {side.upper()}")
        a.add_argument(f"--{side}-param", action="append", type=_param, default=[],
                       metavar="K=V")
    _backend_args(a)
    m = sub.add_parser("matches", help="N matches of two plays, or A/B against an opponent")
    for side in ("a", "b"):
        m.add_argument(f"--{side}", required=True, help=f"play {side.upper()}")
        m.add_argument(f"--{side}-param", action="append", type=_param, default=[],
                       metavar="K=V")
    m.add_argument("--opponent", default=None,
                   help="A/B: A and B each play this opponent on the same seeds")
    m.add_argument("--matches", type=int, default=10)
    m.add_argument("--half-s", type=float, default=90.0, help="a half's playing time (s)")
    m.add_argument("--seed", type=int, default=1)
    m.add_argument("--no-interludes", action="store_true",
                   help="no scripted HALT/STOP/free kick/penalty interludes")
    m.add_argument("--cameras", type=int, choices=[1, 2, 4, 8], default=4,
                   help="fieldsim's cameras (default 4, as make match; 2 halves the vision "
                        "work of both teams' world models)")
    _backend_args(m)
    c = sub.add_parser("class", help="a suite for every student of a class folder")
    c.add_argument("class_dir", type=_user_path, help="one sub-folder per student (their plays)")
    c.add_argument("--suite", default="exercises")
    _backend_args(c)
    sub.add_parser("list", help="the shipped suites and their scenarios")
    args = ap.parse_args(argv)

    if args.cmd == "list":
        for name in shipped_suites():
            suite = load_suite(name)
            runs = sum(sc.runs for sc in suite.scenarios)
            say(f"{name}: {len(suite.scenarios)} scenarios, {runs} runs")
            for sc in suite.scenarios:
                say(f"  {sc.name:<24} {sc.title}" + (f" ({sc.runs} runs)" if sc.runs > 1
                                                      else ""))
        return 0

    if args.out is not None and (args.out / "runs").is_dir() and any((args.out / "runs").iterdir()):
        # the runs' logs are never overwritten (as the recorder's): every run would fail
        say(f"{args.out} holds the runs of an earlier report: give another --out, or remove "
            "it first", err=True)
        return 2

    def progress(done: int, total: int, res: dict[str, Any]) -> None:
        ok = "ok  " if res.get("passed") or ("score" in res and not res.get("error")
                                             and res.get("kind") == "match") else "FAIL"
        extra = ""
        if res.get("kind") == "match" and isinstance(res.get("score"), dict):
            extra = f" {res['blue']} {res['score']['blue']}:{res['score']['yellow']} " \
                    f"{res['yellow']}"
        # a failed run says why on its line: the run's error, the play's failure, or the
        # checks it failed (the report has the rest)
        why = str(res.get("error") or res.get("team_error") or "").strip()
        if not why and ok == "FAIL" and res.get("kind") == "scenario":
            why = "failed: " + ", ".join(str(c.get("label") or c.get("name")) for c in
                                         res.get("checks") or [] if not c.get("passed"))
        err = f"  ({why.splitlines()[0]})" if why and why != "failed: " else ""
        say(f"[{done:>4}/{total}] {ok} {res['name']}{extra} {res.get('wall_s', 0):.1f} s{err}")

    try:
        backend = make_backend(args.cluster, args.workers, args.memory_mb)
    except (OSError, ValueError) as exc:
        say(f"cannot start the backend: {exc}", err=True)
        return 2
    keep = not args.no_logs
    try:
        if args.cmd == "suite":
            suite = load_suite(args.suite)
            names = [sc.name for sc in suite.scenarios]
            unknown = [n for n in args.only if n not in names]
            if unknown:  # else it ran nothing and reported "0/0 runs passed"
                say(f"--only {', '.join(map(repr, unknown))}: no such scenario in the suite "
                    f"{suite.name} (its scenarios: {', '.join(names)}; --only takes one name, "
                    "repeat it for several)", err=True)
                return 2
            out = args.out or default_out(REPORTS, suite.name)
            rep = run_suite(suite, _entrant(args.play, args.param, args.team_dir), out, backend,
                            progress, tuple(args.only), keep)
            t = rep["summary"]["totals"]
            say(f"{t['passed']}/{t['runs']} runs passed, {t['scenarios_passed']}/"
                  f"{t['scenarios']} scenarios, mean score {t['score']}")
        elif args.cmd == "ab":
            suite = load_suite(args.suite)
            out = args.out or default_out(REPORTS, f"{suite.name}-ab")
            rep = run_ab_suite(suite, _entrant(args.a, args.a_param, args.team_dir, "A:" + args.a),
                               _entrant(args.b, args.b_param, args.team_dir, "B:" + args.b),
                               out, backend, progress, keep)
            say(rep["ab"]["difference"]["verdict"])
        elif args.cmd == "matches":
            ea = _entrant(args.a, args.a_param, args.team_dir, "A:" + args.a)
            eb = _entrant(args.b, args.b_param, args.team_dir, "B:" + args.b)
            kw = {"interludes": not args.no_interludes, "cameras": args.cameras}
            if args.opponent:
                out = args.out or default_out(REPORTS, f"ab-vs-{args.opponent}")
                rep = run_ab_matches(ea, eb, Entrant(args.opponent, {}, args.team_dir),
                                     args.matches, args.half_s, args.seed, out, backend,
                                     progress, keep, **kw)
                say(rep["ab"]["difference"]["verdict"])
            else:
                out = args.out or default_out(REPORTS, f"{args.a}-vs-{args.b}")
                rep = run_matches(ea, eb, args.matches, args.half_s, args.seed, out, backend,
                                  progress, keep, **kw)
                sm = rep["summary"]
                say(f"{sm['a']}: {sm['win']} won, {sm['draw']} drawn, {sm['loss']} lost; "
                      f"{sm['difference']['verdict']}")
        elif args.cmd == "class":
            suite = load_suite(args.suite)
            out = args.out or default_out(REPORTS, f"class-{args.class_dir.name}")
            rep = run_class(args.class_dir, suite, out, backend, progress, keep)
            for g in rep["grades"]:
                say(f"{g['student']:<20} {g['score']:.2f}  {g['passed']}/{g['scenarios']}")
        else:  # pragma: no cover
            return 2
    except ScenarioError as exc:
        say(f"bad scenario: {exc}", err=True)
        return 2
    finally:
        backend.close()
    t = rep["timing"]
    say(f"report: {out / 'report.html'} ({t['runs']} runs in {t['wall_s']} s, "
          f"{t['runs_per_minute']} runs/min, {t['speed_vs_real_time']}x real time a worker)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
