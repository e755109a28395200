"""The strategy's outputs on a recording, tick by tick, to compare two versions of the code
(figures for a change that must keep the plans: not a test).

``dump``: runs a fresh ``StrategyCore.decide`` of the code under ``--root`` (a checkout or
worktree; default this one) over the ticks recorded by ``bench/strategy_replay.py record``,
with path reuse on and off, and pickles every tick's moves as plain tuples; then again with
the recorded situation replaced by a few referee situations (stop, their placement, our
kickoff, their free kick, our placement: ball discs, the placement corridor, the wider
margin of the opponents' area), so more of the navigation is compared than a running game
uses.
``diff``: compares two dumps exactly (floats bit for bit) and prints the first differences.

    .venv/bin/python bench/strategy_outputs.py dump --root /work/main --out /tmp/main.out
    .venv/bin/python bench/strategy_outputs.py dump --out /tmp/branch.out
    .venv/bin/python bench/strategy_outputs.py diff /tmp/main.out /tmp/branch.out
"""

from __future__ import annotations

import argparse
import pickle
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
Row = tuple[int, tuple[Any, ...]]


def _plain(m: Any) -> tuple[Any, ...]:
    return (m.role, m.x, m.y, m.orientation, m.path, m.kick_speed_mps, m.chip, m.dribbler,
            m.max_speed_mps, m.blocked)


def dump(a: argparse.Namespace) -> None:
    sys.path.insert(0, str(Path(a.root).resolve()))
    from dataclasses import replace

    import backend.strategy.core as core_mod  # the code under --root
    from backend.strategy.core import StrategyCore
    from backend.strategy.situation import Situation

    print(f"code: {core_mod.__file__}")

    ticks = []
    with open(a.inp, "rb") as f:
        while True:
            try:
                ticks.append(pickle.load(f))
            except (EOFError, pickle.UnpicklingError):
                break
    variants: dict[str, Any] = {
        "": None,
        "stop.": Situation("stop", None, "STOP"),
        "their-placement.": Situation("placement", False, "BALL_PLACEMENT_YELLOW",
                                      designated=(1500.0, -800.0)),
        "our-kickoff-prepare.": Situation("kickoff-prepare", True, "PREPARE_KICKOFF_BLUE"),
        "their-free-kick.": Situation("free-kick", False, "DIRECT_FREE_YELLOW"),
        "our-placement.": Situation("placement", True, "BALL_PLACEMENT_BLUE",
                                    designated=(-2000.0, 1000.0)),
    }
    out: dict[str, list[list[Row]]] = {}
    for name, sit in variants.items():
        for reuse in (True, False):
            core = StrategyCore()
            core.reuse_paths = reuse
            rows = []
            for prep, keeper in ticks:
                if sit is not None:
                    prep = replace(prep, inp=replace(prep.inp, situation=sit))
                moves = core.decide(prep, keeper)
                rows.append([(rid, _plain(m)) for rid, m in moves.items()])
            out[name + ("reuse" if reuse else "fresh")] = rows
    with open(a.out, "wb") as f:
        pickle.dump(out, f)
    print(f"{len(ticks)} ticks from {a.root} -> {a.out}")


def _show(v: Any) -> str:
    return v.hex() if isinstance(v, float) else repr(v)


def diff(a: argparse.Namespace) -> None:
    with open(a.a, "rb") as f:
        da = pickle.load(f)
    with open(a.b, "rb") as f:
        db = pickle.load(f)
    bad = 0
    for mode in da:
        ta, tb = da[mode], db[mode]
        n = sum(len(t) for t in ta)
        diffs = [(i, x, y) for i, (x, y) in enumerate(zip(ta, tb, strict=True)) if x != y]
        print(f"{mode}: {len(ta)} ticks, {n} moves, {len(diffs)} ticks differ")
        for i, x, y in diffs[: a.show]:
            print(f"  tick {i}:")
            for (ra, ma), (rb, mb) in zip(x, y, strict=False):
                if (ra, ma) != (rb, mb):
                    print(f"    robot {ra}/{rb}:\n      a {ma}\n      b {mb}")
        bad += len(diffs)
    raise SystemExit(1 if bad else 0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    d = sub.add_parser("dump")
    d.add_argument("--root", default=str(ROOT))
    d.add_argument("--in", dest="inp", default="/tmp/touchline-strategy.pkl")
    d.add_argument("--out", required=True)
    c = sub.add_parser("diff")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--show", type=int, default=5)
    a = ap.parse_args()
    dump(a) if a.cmd == "dump" else diff(a)


if __name__ == "__main__":
    main()
