"""`python -m match`: play a whole 6 v 6 match on the built-in simulator and print the result.

Starts fieldsim, a relay and two backends (blue: --blue-play, yellow: --yellow-play) on
isolated ports, directs the match (Referee multicast, ball teleports) and judges it from
fieldsim's ground truth. Exit code 0 when the match ran to the end, whatever the score;
1 when a process died or stalled during the match, 2 when something failed to start,
130 when interrupted. See docs/match.md.
"""

from __future__ import annotations

import argparse
import logging
from collections.abc import Sequence
from pathlib import Path

from match.runner import MatchRunner, Options


def _positive(text: str) -> float:
    v = float(text)
    if not v > 0:
        raise argparse.ArgumentTypeError("must be > 0")
    return v


def _speed(text: str) -> float | None:
    """A controller speed limit in m/s (the parameters' range), or 'station'."""
    if text == "station":
        return None
    v = float(text)
    if not 0.05 <= v <= 5.0:
        raise argparse.ArgumentTypeError("must be within 0.05..5 m/s, or 'station'")
    return v


def build_parser() -> argparse.ArgumentParser:
    d = Options()
    p = argparse.ArgumentParser(prog="python -m match", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--minutes", type=_positive, default=d.minutes,
                   help="playing time of the whole match, two halves (default %(default)s)")
    p.add_argument("--seed", type=int, default=d.seed, help="fieldsim's random seed")
    p.add_argument("--division", choices=["A", "B"], default=d.division)
    p.add_argument("--engine", choices=["numpy", "octave"], default=None,
                   help="compute engine of blue's strategy (backend --set strategy.engine=...)")
    p.add_argument("--out", type=Path, default=None,
                   help="write result.json, result.txt, events.csv and the process logs here")
    p.add_argument("--blue-play", default=d.blue_play, help="blue's play (default %(default)s)")
    p.add_argument("--yellow-play", default=d.yellow_play,
                   help="yellow's play (default %(default)s)")
    p.add_argument("--robot-speed", type=_speed, default=d.robot_speed_mps, metavar="MPS",
                   help="speed limit v of every speed controller in both backends (default "
                        "%(default)s m/s; 'station' keeps the station's 1.0 m/s)")
    p.add_argument("--backend-arg", dest="backend_args", action="append", default=[],
                   help="extra flag for both backends (repeatable)")
    p.add_argument("--startup-timeout", type=_positive, default=d.startup_timeout_s,
                   help="seconds to wait for the processes to be ready")
    p.add_argument("--log-level", default="WARNING")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    a = build_parser().parse_args(argv)
    logging.basicConfig(level=a.log_level.upper(),
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    opts = Options(minutes=a.minutes, seed=a.seed, division=a.division, engine=a.engine,
                   out=a.out, blue_play=a.blue_play, yellow_play=a.yellow_play,
                   backend_args=list(a.backend_args), startup_timeout_s=a.startup_timeout,
                   robot_speed_mps=a.robot_speed)
    return MatchRunner(opts).run()


if __name__ == "__main__":
    raise SystemExit(main())
