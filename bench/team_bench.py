"""What hosting a team's code costs (issue 27; figures, not a test).

``reload``: the real station (launcher --isolated, fieldsim, a temporary team folder given
with --team-dir) runs a Python play, then an Octave play; each of ``--saves`` saves writes
the play anew (write-and-rename, as most editors do) with a new target, and the time from
just before the write to the first world answer (GET /api/world, computed on the station
thread when asked) whose targets are the new version's is the reload time: the watcher's
look (every 100 ms), the reload (Python: in the same worker; Octave: a new worker), the next
strategy tick (20 Hz) and the answer. Median and max.

``tick``: in this process, the strategy's part for a team play per tick, 11 v 11, paced at
``--hz``: the host side (the Game built, the request sent, the answer checked and kept
within the envelope: the station thread's own cost) and the round trip (request sent to
answer accounted: pickling, the pipe, the worker's call, its reply), median and p99, for a
trivial Python play and a trivial Octave play. The worker's own CPU time per call too.

``busy``: the shipped ``team/pass_drill.py`` asked at ``--hz`` for ``--seconds`` on a busy
machine: this process (the station's side) and the play's worker share the CPUs ``--cpus``
(default one core, "1") with ``--burners`` busy-looping processes (a laptop at a match
running grSim, the station and a browser), and with ``--stop-every`` > 0 the worker is also
stopped (SIGSTOP) for ``--stop-s`` every so often (a process the OS does not run). Counts:
ticks answered in time, late, the play's failures (each restarts it, as a save would) and
their messages, and why its robots were held. Not part of ``all``.

    PYTHONPATH=. .venv/bin/python bench/team_bench.py [reload|tick|all|busy] [--saves 20]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.station_run import start_station

ROOT = Path(__file__).resolve().parent.parent

PY_PLAY = ("from touchline import Target\n"
           "X = {x}\n"
           "def play(game):\n"
           "    return {{rid: Target(X, -2000.0 + 400.0 * k, 0.0, role='bench')\n"
           "            for k, rid in enumerate(sorted(game.mine))}}\n")
M_PLAY = """function orders = bench_m(ours, theirs, ball, game)
  mine = sort(ours(ours(:, 9) == 1, 1));
  orders = zeros(numel(mine), 9);
  for k = 1:numel(mine)
    orders(k, :) = [mine(k) 0 {x} (-2000 + 400 * (k - 1)) 0 NaN 0 0 0];
  end
end
"""


def pct(values: list[float], q: float) -> float:
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))]


def loadavg() -> str:
    try:
        return Path("/proc/loadavg").read_text().split(" ", 3)[:3].__str__()
    except OSError:
        return "?"


def write_like_an_editor(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.swp")
    tmp.write_text(text)
    os.replace(tmp, path)


# ---------------------------------------------------------------------------- reload


def reload_bench(saves: int) -> dict[str, Any]:
    team = Path(tempfile.mkdtemp(prefix="touchline-team-bench-"))
    (team / "bench_py.py").write_text(PY_PLAY.format(x=-1000.0))
    (team / "bench_m.m").write_text(M_PLAY.format(x=-1000))
    station = start_station(
        ["--team-dir", str(team), "--backend-arg=--play", "--backend-arg=bench_py"],
        stderr=subprocess.STDOUT, env={"PYTHONUNBUFFERED": "1"})
    url = station.url
    out: dict[str, Any] = {}
    try:
        with httpx.Client(base_url=url, timeout=5.0) as c:
            def targets_x() -> set[float]:
                w = c.get("/api/world").json()
                return {r["target"]["x"] for r in w["robots"]
                        if r["team"] == "blue" and r["target"] and r["role"] in ("bench", "team")}

            def wait_for(x: float, limit_s: float = 30.0) -> float:
                t0 = time.monotonic()
                while time.monotonic() - t0 < limit_s:
                    got = targets_x()
                    if got == {x}:
                        return time.monotonic()
                    time.sleep(0.01)  # (not faster: each read runs on the station's loop)
                files = c.get("/api/team").json()["files"]
                raise SystemExit(f"targets never became {x}: "
                                 f"{[(f['name'], f['state'], f['error']) for f in files]}")

            for play, name, template in (("bench_py", "bench_py.py", PY_PLAY),
                                         ("bench_m", "bench_m.m", M_PLAY)):
                c.patch("/api/params", json={"strategy": {"play": play}}).raise_for_status()
                wait_for(-1000.0 if play == "bench_py" else -1000, 60.0)
                times: list[float] = []
                for k in range(1, saves + 1):
                    x = -1000.0 - 10.0 * k
                    text = template.format(x=x if play == "bench_py" else int(x))
                    t_save = time.monotonic()
                    write_like_an_editor(team / name, text)
                    times.append((wait_for(x) - t_save) * 1000.0)
                out[play] = {"median_ms": statistics.median(times), "max_ms": max(times),
                             "min_ms": min(times), "n": len(times)}
                print(f"reload {name}: save -> first tick with the new version "
                      f"median {out[play]['median_ms']:.0f} ms, max "
                      f"{out[play]['max_ms']:.0f} ms, min {out[play]['min_ms']:.0f} ms "
                      f"({len(times)} saves)", flush=True)
    finally:
        station.stop(15)
    return out


# ---------------------------------------------------------------------------- per tick


async def tick_bench(ticks: int, hz: float) -> dict[str, Any]:
    from backend.params.model import PLAYS, StationParams
    from backend.strategy.core import StrategyCore
    from backend.teamcode.envelope import Rules
    from backend.teamcode.game import build_game
    from backend.teamcode.plays import TeamPlays
    from backend.teamcode.registry import TeamRegistry
    from backend.world.state import BallState, RobotState, WorldState

    team = Path(tempfile.mkdtemp(prefix="touchline-team-bench-"))
    (team / "bench_py.py").write_text(PY_PLAY.format(x=-1000.0))
    (team / "bench_m.m").write_text(M_PLAY.format(x=-1000))
    reg = TeamRegistry(team, PLAYS)
    reg.rescan()
    plays = TeamPlays(reg, 1024)
    params = StationParams.model_validate({"strategy": {"play": "bench_py"}})
    core = StrategyCore()
    out: dict[str, Any] = {}
    try:
        for play, name in (("bench_py", "bench_py.py"), ("bench_m", "bench_m.m")):
            host: list[float] = []
            trip: list[float] = []
            cpu: list[float] = []
            groups = {play: tuple(range(11))}
            n = -50  # warm-up ticks first (the worker starts: not counted)
            period = 1.0 / hz
            next_t = time.monotonic()
            while n < ticks:
                now = time.time()
                robots = tuple(RobotState(team_, i, -4000.0 + 700.0 * i, 100.0 * i, 0.0,
                                          t_seen=now)
                               for team_ in ("blue", "yellow") for i in range(11))
                world = WorldState(now, time.time_ns(), BallState(100.0, 50.0, t_seen=now),
                                   robots)
                prep = core.prepare(world, None, None, params.strategy, "blue", True, False,
                                    time.monotonic())
                t0 = time.perf_counter()
                game = build_game(prep, world, None, "blue")
                tick = plays.ask(game, groups, 0.05, 1.0)
                t1 = time.perf_counter()
                await tick.wait()
                t2 = time.perf_counter()
                sit = prep.inp.situation
                rules = Rules(prep.inp.fs, sit.kind, sit.ours, None, None, 0, 650.0)
                orders = tick.orders(rules, {b.id: b for b in prep.inp.ours})
                t3 = time.perf_counter()
                ask = tick.asks[0]
                if ask.pending is not None and ask.pending.output is not None \
                        and len(orders.intents) == 11:
                    if n >= 0:
                        host.append(((t1 - t0) + (t3 - t2)) * 1000.0)
                        trip.append((t2 - t1) * 1000.0)
                        if ask.pending.cpu_ms is not None:
                            cpu.append(ask.pending.cpu_ms)
                    n += 1
                next_t += period
                await asyncio.sleep(max(0.0, next_t - time.monotonic()))
            out[play] = {"host_ms_p50": statistics.median(host), "host_ms_p99": pct(host, 0.99),
                         "round_trip_ms_p50": statistics.median(trip),
                         "round_trip_ms_p99": pct(trip, 0.99),
                         "worker_ms_p50": statistics.median(cpu) if cpu else None,
                         "n": len(host)}
            o = out[play]
            worker = "?" if o["worker_ms_p50"] is None else f"{o['worker_ms_p50']:.3f}"
            print(f"tick {name} (11 robots, {hz:g} Hz, {len(host)} ticks): host side "
                  f"p50 {o['host_ms_p50']:.3f} ms, p99 {o['host_ms_p99']:.3f} ms; round trip "
                  f"p50 {o['round_trip_ms_p50']:.2f} ms, p99 {o['round_trip_ms_p99']:.2f} ms; "
                  f"the call in the worker p50 {worker} ms", flush=True)
            run = reg.runs[name]
            assert run.error is None, run.error
    finally:
        await plays.close()
    return out


# ---------------------------------------------------------------------------- busy


async def busy_bench(seconds: float, hz: float, stop_every_s: float, stop_s: float
                     ) -> dict[str, Any]:
    import collections
    import shutil
    import signal

    from backend.params.model import PLAYS, StationParams
    from backend.strategy.core import StrategyCore
    from backend.teamcode.plays import TeamPlays
    from backend.teamcode.registry import TeamRegistry

    team = Path(tempfile.mkdtemp(prefix="touchline-team-busy-"))
    shutil.copy(ROOT / "team" / "pass_drill.py", team / "pass_drill.py")
    reg = TeamRegistry(team, PLAYS)
    reg.rescan()
    plays = TeamPlays(reg, 1024)
    params = StationParams.model_validate({"strategy": {"play": "pass_drill"}})
    core = StrategyCore()
    groups = {"pass_drill": (0, 1, 2, 3, 4, 5)}
    held: collections.Counter[str] = collections.Counter()
    failures: list[str] = []
    answered = asked = 0
    pids: set[int] = set()
    stopped_pid = 0
    next_stop = time.monotonic() + stop_every_s if stop_every_s > 0 else float("inf")
    resume_at = float("inf")
    period = 1.0 / hz
    try:
        # started and loaded first (not counted)
        deadline = time.monotonic() + 120.0
        while reg.runs.get("pass_drill.py") is None or reg.runs["pass_drill.py"].ticks < 5:
            if time.monotonic() > deadline:
                raise RuntimeError("pass_drill never answered")
            await _busy_tick(core, params, plays, groups)
            await asyncio.sleep(period)
        run = reg.runs["pass_drill.py"]
        late0, errors0 = run.late, run.errors
        end = time.monotonic() + seconds
        next_t = time.monotonic()
        while time.monotonic() < end:
            r = plays.runners["pass_drill.py"]
            now = time.monotonic()
            pid = getattr(r, "pid", 0)
            if pid:
                pids.add(pid)
            if now >= next_stop and pid and not stopped_pid:
                os.kill(pid, signal.SIGSTOP)
                stopped_pid, resume_at = pid, now + stop_s
                next_stop = now + stop_every_s
            if stopped_pid and now >= resume_at:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(stopped_pid, signal.SIGCONT)
                stopped_pid, resume_at = 0, float("inf")
            tick = await _busy_tick(core, params, plays, groups)
            asked += 1
            a = tick.asks[0]
            if a.pending is not None and a.pending.output is not None:
                answered += 1
            else:
                why = a.reason if a.pending is None else a.pending.reason
                held[why.split(" (")[0].split(":")[0]] += 1
            if run.state == "error" and run.error is not None:
                failures.append(run.error.one_line())
                r.update(reg.plays()["pass_drill"])  # as a save would: started again
            next_t += period
            await asyncio.sleep(max(0.0, next_t - time.monotonic()))
        if stopped_pid:
            with contextlib.suppress(ProcessLookupError):
                os.kill(stopped_pid, signal.SIGCONT)
        out = {"seconds": seconds, "hz": hz, "ticks": asked, "answered_in_time": answered,
               "late": run.late - late0, "failures": len(failures),
               "errors_counted": run.errors - errors0, "failure_messages": failures[:5],
               "held_because": dict(held), "workers": len(pids)}
        print(f"busy: {asked} ticks of pass_drill at {hz:g} Hz in {seconds:g} s: "
              f"{answered} answered in time, {out['late']} late, {len(failures)} failures "
              f"({len(pids)} worker process(es)); held because: {dict(held)}", flush=True)
        for m in failures[:5]:
            print(f"  failure: {m}", flush=True)
        return out
    finally:
        await plays.close()


async def _busy_tick(core: Any, params: Any, plays: Any, groups: Any) -> Any:
    from backend.teamcode.game import build_game
    from backend.world.state import BallState, RobotState, WorldState

    now = time.time()
    robots = tuple(RobotState(team_, i, -4000.0 + 700.0 * i, 100.0 * i, 0.0, t_seen=now)
                   for team_ in ("blue", "yellow") for i in range(6))
    world = WorldState(now, time.time_ns(), BallState(-1500.0, 50.0, t_seen=now), robots)
    prep = core.prepare(world, None, None, params.strategy, "blue", True, False,
                        time.monotonic())
    tick = plays.ask(build_game(prep, world, None, "blue"), groups,
                     params.strategy.team_budget_ms / 1000.0, 1.0)
    await tick.wait()
    return tick


def burners(n: int) -> list[subprocess.Popen[bytes]]:
    """``n`` busy-looping processes (inheriting this process's CPU affinity)."""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("part", nargs="?", default="all",
                   choices=["reload", "tick", "all", "busy"])
    p.add_argument("--saves", type=int, default=20)
    p.add_argument("--ticks", type=int, default=600)
    p.add_argument("--hz", type=float, default=20.0)
    p.add_argument("--json", default=None, help="write the figures to this file")
    p.add_argument("--seconds", type=float, default=60.0, help="busy: how long")
    p.add_argument("--burners", type=int, default=4, help="busy: busy-looping processes")
    p.add_argument("--cpus", default="1", help="busy: the CPUs shared (e.g. 1 or 0,1)")
    p.add_argument("--stop-every", type=float, default=0.0,
                   help="busy: SIGSTOP the worker this often (s; 0: never)")
    p.add_argument("--stop-s", type=float, default=1.5, help="busy: for this long")
    a = p.parse_args()
    print(f"load average before: {loadavg()}", flush=True)
    res: dict[str, Any] = {}
    if a.part in ("tick", "all"):
        res["tick"] = asyncio.run(tick_bench(a.ticks, a.hz))
    if a.part in ("reload", "all"):
        res["reload"] = reload_bench(a.saves)
    if a.part == "busy":
        os.sched_setaffinity(0, {int(c) for c in a.cpus.split(",")})
        procs = burners(a.burners)
        try:
            res["busy"] = asyncio.run(busy_bench(a.seconds, a.hz, a.stop_every, a.stop_s))
        finally:
            for b in procs:
                b.kill()
                b.wait()
    print(f"load average after: {loadavg()}", flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
