"""``python -m ssllog``: ``info FILE`` summarises a log, ``export FILE --csv OUT`` writes the
raw vision detections as CSV (one row per object per camera frame), ``index FILE`` builds the
cache a replay player opens at once later (the station runs it as a child process). The
filters re-run over a log's vision is the backend's command: ``python -m backend.relog``."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from collections.abc import Callable, Sequence

from ssllog.export import export_csv, info, open_for_command, progress_printer, write_csv
from ssllog.logfile import LogFile
from ssllog.reader import LogFormatError

#: ``export --filtered`` moved to the backend (the log package does not import the backend)
FILTERED_MOVED = ("ssllog: --filtered moved: the world model's re-run is the backend's "
                  "command, python -m backend.relog FILE --csv OUT [--filter NAME] "
                  "[--from S] [--to S]\n")


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
    # kept to say where it went rather than argparse's "unrecognized arguments"
    pe.add_argument("--filtered", nargs="?", const="", default=None, help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if getattr(args, "filtered", None) is not None:
        sys.stderr.write(FILTERED_MOVED)
        return 2
    if args.cmd == "index":
        return index(args.file, args.cache_dir, args.nice, args.progress_lines,
                     progress_printer(args.progress or sys.stderr.isatty(), "indexing"))
    show = args.progress or sys.stderr.isatty()
    lf = open_for_command(args.file, args.cache_dir, show)
    if lf is None:
        return 1
    with lf:
        if args.cmd == "info":
            info(lf, sys.stdout)
            return 0
        write_csv(lf, args.csv, lambda lf, out, prog: export_csv(
            lf, out, args.t_from, args.t_to, prog), show)
    return 0

if __name__ == "__main__":
    sys.exit(main())
