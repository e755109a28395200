"""What ``python -m ssllog`` writes, as functions other commands build on: the summary of a
log (``info``), the raw vision detections as CSV (``export_csv``), the vision frames of a time
range parsed (``vision_frames``: ``python -m backend.relog`` re-runs the world model over
them) and a progress line for a terminal (``progress_printer``)."""

from __future__ import annotations

import csv
import sys
from collections import Counter
from collections.abc import Callable, Iterator
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


def progress_printer(enabled: bool, label: str) -> Callable[[float], None] | None:
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
    for rec, wrapper in vision_frames(lf, t_from, t_to, (TYPE_VISION_2014, TYPE_VISION_2010),
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


def vision_frames(
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


#: writes the CSV rows of a log to ``out`` with a progress callback; returns how many
RowWriter = Callable[[LogFile, TextIO, Callable[[float], None] | None], int]


def open_for_command(path: str, cache_dir: str, show_progress: bool,
                     prog: str = "ssllog") -> LogFile | None:
    """Opens a log for a command line (indexing progress on stderr); None after one line on
    stderr naming ``prog`` and the reason (a missing or corrupt file)."""
    try:
        return LogFile.open(path, cache_dir, progress_printer(show_progress, "indexing"))
    except (OSError, LogFormatError) as e:
        sys.stderr.write(f"{prog}: {e}\n")
        return None


def write_csv(lf: LogFile, csv_path: str, rows_of: RowWriter, show_progress: bool) -> int:
    """Writes ``rows_of``'s CSV to ``csv_path`` ('-': stdout), then the row count and the
    log's warning (a truncated tail) on stderr; returns the row count."""
    prog = progress_printer(show_progress, "exporting")
    if csv_path == "-":
        rows = rows_of(lf, sys.stdout, prog)
    else:
        with open(csv_path, "w", newline="") as out:
            rows = rows_of(lf, out, prog)
    sys.stderr.write(f"{rows} rows\n")
    if lf.warning:
        sys.stderr.write(f"warning: {lf.warning}\n")
    return rows
