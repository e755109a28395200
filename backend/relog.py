"""``python -m backend.relog FILE --csv OUT``: Touchline's world model re-run over the vision of
an SSL log (ours or the league's) with one filter for every object, written as CSV: one row
per object after every camera frame merged (positions, orientations, velocities), for MATLAB
or pandas. The raw detections are ``python -m ssllog export``; this command is the backend's
because it runs the backend's world model over what the log package reads."""

from __future__ import annotations

import argparse
import csv
import os
import sys
import tempfile
from collections.abc import Callable, Sequence
from typing import TextIO, get_args

from ssllog.export import open_for_command, vision_frames, write_csv
from ssllog.format import TYPE_VISION_2014
from ssllog.logfile import LogFile

from .filters.params import FilterKind, FilterSettings
from .replay.history import merge_wrapper
from .world.model import WorldModel

FILTERED_COLUMNS = (
    "t_log_s", "t_capture", "kind", "id", "x_mm", "y_mm", "orientation_rad",
    "vx_mm_s", "vy_mm_s", "omega_rad_s", "visible",
)


def export_filtered(
    lf: LogFile,
    out: TextIO,
    t_from: float | None,
    t_to: float | None,
    filter_name: FilterKind,
    progress: Callable[[float], None] | None = None,
) -> int:
    """The world model (``filter_name`` for the ball and every robot) over the vision records
    between ``t_from`` and ``t_to`` (s from the log's start); returns the rows written."""
    model = WorldModel()
    model.configure(FilterSettings(ball=filter_name, robot=filter_name))
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(FILTERED_COLUMNS)
    rows = 0
    for rec, wrapper in vision_frames(lf, t_from, t_to, (TYPE_VISION_2014,), progress):
        if not merge_wrapper(model, wrapper, rec.time_ns):
            continue
        w = model.snapshot()
        head = (f"{(rec.time_ns - lf.t_first_ns) / 1e9:.6f}", repr(w.t_capture))
        if w.ball is not None:
            b = w.ball
            writer.writerow((*head, "ball", "", b.x, b.y, "", b.vx, b.vy, "", int(b.visible)))
            rows += 1
        for r in w.robots:
            writer.writerow((*head, r.team, r.id, r.x, r.y, r.orientation, r.vx, r.vy, r.omega,
                             int(r.visible)))
            rows += 1
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m backend.relog", description=__doc__)
    p.add_argument("file")
    p.add_argument("--csv", required=True, help="output file ('-' for stdout)")
    p.add_argument("--filter", default="kalman", choices=get_args(FilterKind),
                   help="the filter of every object (default %(default)s; 'paper' is the "
                        "paper's median + weighted average)")
    p.add_argument("--from", dest="t_from", type=float, help="seconds from the log's start")
    p.add_argument("--to", dest="t_to", type=float, help="seconds from the log's start")
    p.add_argument("--cache-dir", default=os.path.join(tempfile.gettempdir(), "ssllog-cache"),
                   help="where gzip copies and indexes are kept (default %(default)s; the "
                        "same as python -m ssllog's)")
    p.add_argument("--progress", action="store_true", help="progress on stderr even if no tty")
    args = p.parse_args(argv)
    show = args.progress or sys.stderr.isatty()
    lf = open_for_command(args.file, args.cache_dir, show, "relog")
    if lf is None:
        return 1
    with lf:
        write_csv(lf, args.csv, lambda lf, out, prog: export_filtered(
            lf, out, args.t_from, args.t_to, args.filter, prog), show)
    return 0


if __name__ == "__main__":
    sys.exit(main())
