"""``python -m ssllog``: ``info FILE`` summarises a log, ``export FILE --csv OUT`` writes the
raw vision detections as CSV (one row per object per camera frame), ``index FILE`` builds the
cache a replay player opens at once later (the station runs it as a child process)."""

from __future__ import annotations

import argparse
import csv
import os
import sys
import tempfile
from collections import Counter
from collections.abc import Callable, Iterator, Sequence
from typing import TextIO

from domain.wallclock import iso_utc
from ssllog.format import TYPE_VISION_2010, TYPE_VISION_2014
from ssllog.logfile import TYPE_NAMES, LogFile
from ssllog.reader import LogFormatError, Record
from sslpb import ssl_vision_wrapper_pb2

CSV_COLUMNS = (
    "t_log_s", "t_capture", "camera_id", "frame_number", "kind", "id",
    "x_mm", "y_mm", "orientation_rad", "confidence",
)


def _progress_printer(enabled: bool, label: str) -> Callable[[float], None] | None:
    """A ``\\r`` percentage line on stderr; None when disabled (no tty, no --progress)."""
    if not enabled:
        return None
    last = [-1]

    def show(fraction: float) -> None:
        pct = int(fraction * 100)
        if pct != last[0]:
            last[0] = pct
            sys.stderr.write(f"\r{label} {pct:3d}%")
            if pct >= 100:
                sys.stderr.write("\n")
            sys.stderr.flush()

    return show


def _utc(ns: int) -> str:
    return iso_utc(ns / 1e9)


def info(lf: LogFile, out: TextIO) -> None:
    w = out.write
    w(f"file: {lf.path}\n")
    if lf.data_path != lf.path:
        w(f"plain copy: {lf.data_path}\n")
    w(f"duration: {lf.duration_s:.3f} s ({_utc(lf.t_first_ns)} .. {_utc(lf.t_last_ns)})\n")
    w("messages:\n")
    for t, n in sorted(lf.counts.items()):
        name = TYPE_NAMES.get(t, "unknown type")
        w(f"  {t:5d} {name:14s} {n}\n")
    w("cameras:\n")
    for cam, n in sorted(lf.cameras.items()):
        rate = n / lf.duration_s if lf.duration_s > 0 else 0.0
        w(f"  camera {cam}: {n} frames, {rate:.1f} Hz\n")
    teams = lf.teams
    w(f"teams: yellow {teams.get('yellow', '?')}, blue {teams.get('blue', '?')}\n")
    events = lf.events
    for kind in ("stage", "command", "goal", "card"):
        c = Counter(e.label for e in events if e.kind == kind)
        seen = ", ".join(f"{label} x{n}" for label, n in sorted(c.items()))
        w(f"{kind}s: {seen or '-'}\n")
    gaps = lf.gaps
    w(f"gaps (> 1 s without vision): {len(gaps)}\n")
    for a, b in gaps:
        w(f"  {(a - lf.t_first_ns) / 1e9:.3f} s .. {(b - lf.t_first_ns) / 1e9:.3f} s "
          f"({(b - a) / 1e9:.3f} s)\n")
    if lf.warning:
        w(f"warning: {lf.warning}\n")


def export_csv(
    lf: LogFile,
    out: TextIO,
    t_from: float | None,
    t_to: float | None,
    progress: Callable[[float], None] | None = None,
) -> int:
    """Writes the CSV rows; returns how many. --from/--to are seconds from the log's start."""
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    rows = 0
    for rec, wrapper in _vision(lf, t_from, t_to, (TYPE_VISION_2014, TYPE_VISION_2010),
                                progress):
        if not wrapper.HasField("detection"):
            continue
        d = wrapper.detection
        t_log = f"{(rec.time_ns - lf.t_first_ns) / 1e9:.6f}"
        head = (t_log, repr(d.t_capture), d.camera_id, d.frame_number)
        for b in d.balls:
            writer.writerow((*head, "ball", "", b.x, b.y, "", b.confidence))
            rows += 1
        for kind, robots in (("blue", d.robots_blue), ("yellow", d.robots_yellow)):
            for r in robots:
                orientation = r.orientation if r.HasField("orientation") else ""
                writer.writerow((*head, kind, r.robot_id, r.x, r.y, orientation, r.confidence))
                rows += 1
    return rows


def _vision(
    lf: LogFile,
    t_from: float | None,
    t_to: float | None,
    types: tuple[int, ...],
    progress: Callable[[float], None] | None,
) -> Iterator[tuple[Record, ssl_vision_wrapper_pb2.SSL_WrapperPacket]]:
    """The vision records between --from and --to (s from the log's start), parsed (a garbled
    one is skipped; the wrapper object is reused), with the progress by bytes."""
    start = lf.offset_at(lf.t_first_ns + round(t_from * 1e9)) if t_from is not None else None
    end_ns = lf.t_first_ns + round(t_to * 1e9) if t_to is not None else None
    first_off = start if start is not None else 0
    span = max(1, lf.data_end - first_off)
    wrapper = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    for n, rec in enumerate(lf.records(start)):
        if end_ns is not None and rec.time_ns > end_ns:
            break
        if progress is not None and n % 4096 == 0:
            progress((rec.offset - first_off) / span)
        if rec.type not in types:
            continue
        try:
            wrapper.ParseFromString(rec.payload)
        except Exception:  # a garbled frame is skipped
            continue
        yield rec, wrapper
    if progress is not None:
        progress(1.0)


FILTERED_COLUMNS = (
    "t_log_s", "t_capture", "kind", "id", "x_mm", "y_mm", "orientation_rad",
    "vx_mm_s", "vy_mm_s", "omega_rad_s", "visible",
)


def export_filtered(
    lf: LogFile,
    out: TextIO,
    t_from: float | None,
    t_to: float | None,
    filter_name: str,
    progress: Callable[[float], None] | None = None,
) -> int:
    """Touchline's world model re-run over the vision (the paper's filters or the Kalman
    filter, for every object): one row per object after every camera frame merged."""
    from backend.filters.params import FilterSettings
    from backend.replay.history import merge_wrapper
    from backend.world.model import WorldModel

    model = WorldModel()
    model.configure(FilterSettings(ball=filter_name, robot=filter_name))  # type: ignore[arg-type]
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(FILTERED_COLUMNS)
    rows = 0
    for rec, wrapper in _vision(lf, t_from, t_to, (TYPE_VISION_2014,), progress):
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


def index(path: str, cache_dir: str, nice: int, lines: bool,
          printer: Callable[[float], None] | None) -> int:
    """Builds the cache of ``path`` (the slow pass) and closes it. With ``lines``, progress
    goes to stdout as 'progress F' (a parent that has gone away ends this one at the next
    line: the write fails)."""
    if nice:
        os.nice(nice)
    def line(fraction: float) -> None:
        sys.stdout.write(f"progress {fraction:.4f}\n")
        sys.stdout.flush()

    try:
        LogFile.open(path, cache_dir, line if lines else printer).close()
    except (OSError, LogFormatError) as e:
        sys.stderr.write(f"ssllog: {e}\n")
        return 1
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m ssllog", description=__doc__)
    p.add_argument("--cache-dir", default=os.path.join(tempfile.gettempdir(), "ssllog-cache"),
                   help="where gzip copies and indexes are kept (default %(default)s)")
    p.add_argument("--progress", action="store_true", help="progress on stderr even if no tty")
    sub = p.add_subparsers(dest="cmd", required=True)
    pi = sub.add_parser("info", help="duration, messages, cameras, teams, stages, commands, gaps")
    pi.add_argument("file")
    px = sub.add_parser("index", help="only build the gzip copy and the index in the cache")
    px.add_argument("file")
    px.add_argument("--progress-lines", action="store_true",
                    help="'progress F' lines (F in 0..1) on stdout, for a parent process")
    px.add_argument("--nice", type=int, default=0,
                    help="lower this process's priority by N first (background work)")
    pe = sub.add_parser("export", help="vision detections as CSV")
    pe.add_argument("file")
    pe.add_argument("--from", dest="t_from", type=float, help="seconds from the log's start")
    pe.add_argument("--to", dest="t_to", type=float, help="seconds from the log's start")
    pe.add_argument("--csv", required=True, help="output file ('-' for stdout)")
    pe.add_argument("--filtered", nargs="?", const="kalman", default=None,
                    choices=["raw", "median", "paper", "kalman"],
                    help="instead of the raw detections, Touchline's world model re-run over "
                         "them with this filter for every object (default kalman; 'paper' is "
                         "the paper's median + weighted average): positions and velocities")
    args = p.parse_args(argv)
    if args.cmd == "index":
        return index(args.file, args.cache_dir, args.nice, args.progress_lines,
                     _progress_printer(args.progress or sys.stderr.isatty(), "indexing"))
    show = args.progress or sys.stderr.isatty()
    try:
        lf = LogFile.open(args.file, args.cache_dir, _progress_printer(show, "indexing"))
    except (OSError, LogFormatError) as e:
        sys.stderr.write(f"ssllog: {e}\n")
        return 1
    with lf:
        if args.cmd == "info":
            info(lf, sys.stdout)
            return 0
        prog = _progress_printer(show, "exporting")

        def export(out: TextIO) -> int:
            if args.filtered is not None:
                return export_filtered(lf, out, args.t_from, args.t_to, args.filtered, prog)
            return export_csv(lf, out, args.t_from, args.t_to, prog)
        if args.csv == "-":
            rows = export(sys.stdout)
        else:
            with open(args.csv, "w", newline="") as out:
                rows = export(out)
        sys.stderr.write(f"{rows} rows\n")
        if lf.warning:
            sys.stderr.write(f"warning: {lf.warning}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
