"""This process's CPU and memory, as the Health tab shows them for each process."""

from __future__ import annotations

import os
import time

_PAGE = os.sysconf("SC_PAGE_SIZE")


class CpuMeter:
    """CPU of this process (every thread) in % of one core, over the interval since the
    previous reading (the first reading covers the time since the meter was made)."""

    def __init__(self) -> None:
        self._cpu = time.process_time()
        self._wall = time.monotonic()
        self.percent = 0.0

    def read(self, min_interval_s: float = 0.5) -> float:
        """The % since the previous reading, or the previous figure if that was too recent
        (several readers a second must not make the interval tiny)."""
        cpu, wall = time.process_time(), time.monotonic()
        if wall - self._wall >= min_interval_s:
            self.percent = (cpu - self._cpu) / (wall - self._wall) * 100.0
            self._cpu, self._wall = cpu, wall
        return self.percent


def rss_mb() -> float:
    """Resident memory now (MB), from /proc; 0 where there is none."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * _PAGE / 2**20
    except (OSError, ValueError, IndexError):
        return 0.0


def thread_cpu_s(pid: int) -> dict[tuple[str, int], float]:
    """CPU seconds (user + system) of each thread of process ``pid`` so far, keyed by the
    thread's OS name and id, from /proc (benches read two of these over an interval; a thread
    that ends meanwhile is left out)."""
    ticks = os.sysconf("SC_CLK_TCK")
    out: dict[tuple[str, int], float] = {}
    try:
        tasks = list(os.scandir(f"/proc/{pid}/task"))
    except OSError:
        return out
    for task in tasks:
        try:
            with open(os.path.join(task.path, "stat")) as f:
                stat = f.read()
        except OSError:
            continue
        name = stat[stat.index("(") + 1:stat.rindex(")")]
        fields = stat.rsplit(")", 1)[1].split()
        out[(name, int(task.name))] = (int(fields[11]) + int(fields[12])) / ticks
    return out


def process_cpu_s(pid: int) -> float:
    """CPU seconds (user + system, every thread) of process ``pid`` so far, from /proc."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
