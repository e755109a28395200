"""The result of a match: the plain-text table printed at the end, result.json and events.csv."""

from __future__ import annotations

import csv
import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from match.stats import EPISODE_KINDS, VIOLATION_KINDS

VIOLATION_LABELS = {
    "halt_moving": "HALT: moving after the grace",
    "stop_speed": "STOP: faster than 1.5 m/s",
    "stop_distance": "STOP: closer than 0.5 m to the ball",
    "set_piece_distance": "opponent free kick/kick-off: < 0.5 m",
    "placement_distance": "opponent placement: < 0.5 m",
    "defense_area": "defence area touched",
    "kickoff_position": "kick-off position (per robot)",
    "penalty_position": "penalty position (per robot)",
    "collision": "collision > 1.5 m/s",
}
TIMELINE_FIELDS = ("t", "kind", "team", "robot", "command", "stage", "detail")


def table(headers: Sequence[str], rows: Sequence[Sequence[str]], left: int = 1) -> str:
    """Aligned columns: the first ``left`` columns left-aligned, the others right-aligned."""
    widths = [len(h) for h in headers]
    for row in rows:
        widths = [max(w, len(c)) for w, c in zip(widths, row, strict=True)]

    def line(cells: Sequence[str]) -> str:
        out = [c.ljust(w) if i < left else c.rjust(w)
               for i, (c, w) in enumerate(zip(cells, widths, strict=True))]
        return "  ".join(out).rstrip()

    return "\n".join([line(headers), line(["-" * w for w in widths]),
                      *(line(r) for r in rows)])


def _num(v: Any, fmt: str = "{:.1f}", none: str = "n/a") -> str:
    return none if v is None else fmt.format(v)


def format_result(res: dict[str, Any]) -> str:
    teams: dict[str, Any] = res.get("teams", {})
    opts: dict[str, Any] = res.get("options", {})
    blue, yellow = teams.get("blue", {}), teams.get("yellow", {})
    status = "finished" if res.get("finished") else f"NOT FINISHED ({res.get('reason', '?')})"
    head = (f"Touchline match: blue ({blue.get('play', '?')}) {blue.get('goals', 0)} : "
            f"{yellow.get('goals', 0)} yellow ({yellow.get('play', '?')})   -- {status}")
    sub = []
    if opts:
        speed = opts.get("robot_speed_mps")
        sub.append(f"division {opts.get('division')}, {opts.get('minutes')} min "
                   f"(2 halves), seed {opts.get('seed')}, robots at "
                   + (f"{speed} m/s" if speed is not None else "the station's speed"))
    sub.append(f"{res.get('elapsed_s', 0.0):.0f} s on the clock of the director; events from "
               f"{res.get('events_source') or 'nowhere (none seen)'}")
    rows = []
    for name in ("blue", "yellow"):
        t = teams.get(name, {})
        p = t.get("placements", {})
        rows.append([
            name, str(t.get("play", "")), str(t.get("goals", 0)),
            _num(t.get("possession_pct"), "{:.1f} %"),
            _num(t.get("kicks"), "{:d}"),
            f"{p.get('ok', 0)} / {p.get('failed', 0)}",
            _num(p.get("mean_time_s"), "{:.1f} s", "-"),
        ])
    main = table(["team", "play", "goals", "possession", "kicks", "placements ok / failed",
                  "mean time"], rows, left=2)
    loose = f"ball loose (nobody within 200 mm) in running play: {res.get('loose_ball_s', 0.0)} s"

    vrows = []
    for kind in VIOLATION_KINDS:
        cells = [VIOLATION_LABELS[kind]]
        for name in ("blue", "yellow"):
            c = teams.get(name, {}).get("violations", {}).get(kind, {})
            n = c.get("count", 0)
            cells.append(f"{n} ({c.get('seconds', 0.0):.1f} s)"
                         if kind in EPISODE_KINDS and n else str(n))
        vrows.append(cells)
    viol = table(["violations (episodes, robot-seconds)",
                  *(f"{n} ({teams.get(n, {}).get('play', '?')})" for n in ("blue", "yellow"))],
                 vrows)

    crows = [[c, str(v.get("count", 0)), f"{v.get('seconds', 0.0):.1f}"]
             for c, v in res.get("commands", {}).items()]
    cmds = table(["command", "issued", "seconds"], crows)
    ev = res.get("events", {})
    events = ", ".join(f"{k} {v}" for k, v in sorted(ev.items())) or "none"
    procs = res.get("processes", {})
    alive = ", ".join(f"{k} {'alive' if p.get('alive_throughout') else 'DIED'}"
                      for k, p in procs.items())
    parts = [head, *sub, "", main, loose, "", viol, "", cmds, "", f"events: {events}"]
    if alive:
        parts.append(f"processes: {alive}")
    return "\n".join(parts) + "\n"


def write_outputs(out: Path, res: dict[str, Any], timeline: list[dict[str, Any]]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / "result.json").write_text(json.dumps(res, indent=2, sort_keys=False) + "\n")
    with (out / "events.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=TIMELINE_FIELDS, extrasaction="ignore")
        w.writeheader()
        for row in timeline:
            w.writerow({k: ("" if row.get(k) is None else row.get(k)) for k in TIMELINE_FIELDS})
    (out / "result.txt").write_text(format_result(res))
