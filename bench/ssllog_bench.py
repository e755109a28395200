"""How fast LogFile is on a match-sized log: index build, random seeks, peak RSS, gzip copy.

Run: ``PYTHONPATH=. .venv/bin/python bench/ssllog_bench.py [--mb 700] [--gz-mb 50]``.
Prints figures only (no asserts on speed); the temp files are deleted at the end."""

from __future__ import annotations

import argparse
import gzip
import math
import os
import random
import resource
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from ssllog.export import export_csv
from ssllog.format import RECORD_HEADER, file_header
from ssllog.logfile import LogFile, _gunzip_copy
from sslpb import ssl_gc_referee_message_pb2, ssl_vision_wrapper_pb2

Referee = ssl_gc_referee_message_pb2.Referee
S = 1_000_000_000
CAMS = 4
VISION_HZ = 60
REFEREE_HZ = 40
COMMANDS = (Referee.STOP, Referee.FORCE_START, Referee.DIRECT_FREE_BLUE, Referee.NORMAL_START,
            Referee.DIRECT_FREE_YELLOW, Referee.BALL_PLACEMENT_BLUE)


def wrapper(cam: int, frame: int, rng: random.Random) -> bytes:
    """One camera frame: ball + 6 blue + 6 yellow robots, all fields a real camera sends."""
    w = ssl_vision_wrapper_pb2.SSL_WrapperPacket()
    d = w.detection
    d.frame_number = frame
    d.t_capture = 1.7e9 + frame / VISION_HZ
    d.t_sent = d.t_capture + 0.004
    d.t_capture_camera = d.t_capture - 0.001
    d.camera_id = cam
    b = d.balls.add()
    b.confidence, b.area = 0.93, 78
    b.x, b.y, b.z = rng.uniform(-6000, 6000), rng.uniform(-4500, 4500), 0.0
    b.pixel_x, b.pixel_y = rng.uniform(0, 2048), rng.uniform(0, 2048)
    for robots in (d.robots_blue, d.robots_yellow):
        for i in range(6):
            r = robots.add()
            r.confidence, r.robot_id = rng.uniform(0.5, 1.0), i
            r.x, r.y = rng.uniform(-6000, 6000), rng.uniform(-4500, 4500)
            r.orientation = rng.uniform(-math.pi, math.pi)
            r.pixel_x, r.pixel_y, r.height = rng.uniform(0, 2048), rng.uniform(0, 2048), 150.0
    return w.SerializeToString()


def referee(t_ns: int, second: int) -> bytes:
    r = Referee()
    r.packet_timestamp = t_ns // 1000
    r.stage = Referee.NORMAL_FIRST_HALF if second < 2700 else Referee.NORMAL_SECOND_HALF
    r.stage_time_left = (2700 - second % 2700) * 1_000_000
    counter = second // 20
    r.command = COMMANDS[counter % len(COMMANDS)]
    r.command_counter = counter
    r.command_timestamp = t_ns // 1000
    for info, name, goals in ((r.yellow, "TIGERs Mannheim", second // 600),
                              (r.blue, "ER-Force", second // 900)):
        info.name, info.score, info.red_cards, info.yellow_cards = name, goals, 0, second // 1200
        info.timeouts, info.timeout_time, info.goalkeeper = 4, 300_000_000, 1
    return r.SerializeToString()


def build(path: Path, mb: int) -> tuple[int, float]:
    """Writes ~mb MB; returns the record count and the seconds of log time."""
    rng = random.Random(7)
    frames = [[wrapper(c, f, rng) for f in range(VISION_HZ)] for c in range(CAMS)]
    target = mb * 1024 * 1024
    t0 = 1_700_000_000 * S
    n = 0
    size = 0
    second = 0
    pack = RECORD_HEADER.pack
    with open(path, "wb") as f:
        f.write(file_header())
        size = len(file_header())
        while size < target:
            items: list[tuple[int, int, bytes]] = []
            base = t0 + second * S
            for c in range(CAMS):
                for k in range(VISION_HZ):
                    # cameras out of phase, a little receive jitter
                    t = base + k * S // VISION_HZ + c * 3_000_000 + rng.randrange(0, 500_000)
                    items.append((t, 4, frames[c][k]))
            for k in range(REFEREE_HZ):
                t = base + k * S // REFEREE_HZ + 1_000_000
                items.append((t, 3, referee(t, second)))
            items.sort(key=lambda x: x[0])
            chunk = b"".join(pack(t, ty, len(p)) + p for t, ty, p in items)
            f.write(chunk)
            size += len(chunk)
            n += len(items)
            second += 1
    return n, float(second)


def drop_from_page_cache(path: Path) -> None:
    """Asks the kernel to forget this one file's pages, so the next read comes from disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
    finally:
        os.close(fd)


def rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--mb", type=int, default=700, help="size of the plain log")
    ap.add_argument("--gz-mb", type=int, default=50, help="size of the log for the gzip copy")
    ap.add_argument("--seeks", type=int, default=200)
    ap.add_argument("--dir", default=None, help="temp dir parent (default: system temp)")
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="ssllog_bench_", dir=args.dir))
    try:
        log = tmp / "match.log"
        t = time.perf_counter()
        n, secs = build(log, args.mb)
        size = log.stat().st_size
        print(f"built {size / 1e6:.0f} MB, {n} records, {secs / 60:.1f} min of log "
              f"in {time.perf_counter() - t:.1f} s (peak RSS so far {rss_mb():.0f} MB)")

        for cache, label in (("cache-warm", "page cache warm"), ("cache", "file not cached")):
            if cache == "cache":
                drop_from_page_cache(log)
            t = time.perf_counter()
            lf = LogFile.open(str(log), tmp / cache)
            t_index = time.perf_counter() - t
            print(f"index build ({label}): {t_index:.2f} s ({size / 1e6 / t_index:.0f} MB/s), "
                  f"{len(lf.events)} events, cameras {lf.cameras}, gaps {len(lf.gaps)}")
            lf.close()
        drop_from_page_cache(log)
        t = time.perf_counter()
        lf = LogFile.open(str(log), tmp / "cache")
        print(f"second open (index from cache): {(time.perf_counter() - t) * 1000:.0f} ms")

        rng = random.Random(1)
        lat: list[float] = []
        for _ in range(args.seeks):
            target = rng.randrange(lf.t_first_ns, lf.t_last_ns)
            t = time.perf_counter()
            off = lf.offset_at(target)
            rec = lf.read_at(off)
            lat.append((time.perf_counter() - t) * 1000)
            assert rec.time_ns >= target
        lat.sort()
        print(f"offset_at + read next record, {len(lat)} random times (cold file): "
              f"p50 {statistics.median(lat):.3f} ms, p99 {lat[int(len(lat) * 0.99) - 1]:.3f} ms, "
              f"max {lat[-1]:.3f} ms")
        t = time.perf_counter()
        back = lf.offset_at(lf.t_first_ns + (lf.t_last_ns - lf.t_first_ns) // 2)
        for _ in range(100):
            prev = lf.prev_record_offset(back, 4)
            assert prev is not None
            back = prev
        print(f"100 steps one vision frame back: {(time.perf_counter() - t) * 1000:.1f} ms")
        t = time.perf_counter()
        k = sum(1 for _ in zip(range(100_000), lf.records(lf.offset_at(lf.t_first_ns)),
                               strict=False))
        print(f"records(): {k} records streamed in {(time.perf_counter() - t):.2f} s")
        t = time.perf_counter()
        with open(tmp / "x.csv", "w", newline="") as out:
            rows = export_csv(lf, out, 600.0, 660.0)
        print(f"export --from 600 --to 660 (60 s of log): {rows} CSV rows in "
              f"{time.perf_counter() - t:.2f} s")
        lf.close()
        log.unlink()
        print(f"peak RSS: {rss_mb():.0f} MB")

        small = tmp / "small.log"
        build(small, args.gz_mb)
        gz = tmp / "small.log.gz"
        with open(small, "rb") as src, gzip.open(gz, "wb", compresslevel=6) as dst:
            shutil.copyfileobj(src, dst, 4 * 1024 * 1024)
        t = time.perf_counter()
        _gunzip_copy(str(gz), tmp / "copy.log", None)
        t_gz = time.perf_counter() - t
        assert (tmp / "copy.log").stat().st_size == small.stat().st_size
        print(f"gzip copy: {gz.stat().st_size / 1e6:.0f} MB .gz -> "
              f"{small.stat().st_size / 1e6:.0f} MB plain in {t_gz:.2f} s "
              f"({small.stat().st_size / 1e6 / t_gz:.0f} MB/s plain)")
        t = time.perf_counter()
        with LogFile.open(str(gz), tmp / "cache2") as lf2:
            print(f"LogFile.open(.gz) first time (copy + index): "
                  f"{time.perf_counter() - t:.2f} s, {sum(lf2.counts.values())} records")
        print(f"peak RSS at the end: {rss_mb():.0f} MB")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        os.sync()


if __name__ == "__main__":
    main()
