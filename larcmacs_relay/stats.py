"""The statistics: ``RelayStats`` on the PUB's "stats" topic every ``stats_interval_s`` (and
at once after an arming change: safety.py), every stream's counters, the robots' states, the
output rate, the command latency and the latches.
"""

from __future__ import annotations

import time
from collections import deque

from larcmacs_relay.commands import RobotState
from larcmacs_relay.part import RelayPart
from sslnet import proc
from sslnet.streams import StreamCounter
from sslpb import touchline_pb2


def stream_proto(c: StreamCounter, now: float) -> touchline_pb2.StreamStats:
    """One stream's counters as published in RelayStats."""
    return touchline_pb2.StreamStats(
        name=c.name,
        packets=c.packets,
        errors=c.errors,
        bytes=c.bytes,
        rate_hz=c.rate.rate_hz(now),
        last_age_s=c.rate.age_s(now),
        last_error=c.last_error,
        errors_by_reason=c.by_reason,
    )


class Statistics(RelayPart):
    """RelayStats, made and published."""

    cpu: proc.CpuMeter

    def _setup_stats(self) -> None:
        self.cpu = proc.CpuMeter()
        self._latencies = deque()

    def stats(self, now: float | None = None) -> touchline_pb2.RelayStats:
        t = time.monotonic() if now is None else now
        while self._latencies and self._latencies[0][0] < t - 1.0:
            self._latencies.popleft()
        lat = sorted(v for _, v in self._latencies)
        latency = sum(lat) / len(lat) if lat else -1.0
        p50 = lat[len(lat) // 2] if lat else -1.0
        p99 = lat[min(len(lat) - 1, int(0.99 * len(lat)))] if lat else -1.0
        return touchline_pb2.RelayStats(
            time_ns=time.time_ns(),
            streams=[stream_proto(s, t) for s in self.streams.values()],
            output_mode=self.config.output,
            active_robots=self.table.count(RobotState.ACTIVE),
            stale_robots=self.table.count(RobotState.STALE) + self.table.count(RobotState.STOPPED),
            output_rate_hz=self.cycles.rate_hz(t),
            command_latency_ms=latency,
            stale_stops=self.table.stale_stops,
            estop_latched=self.estop_latched,
            estop_by=self.estop_by,
            command_latency_p50_ms=p50,
            command_latency_p99_ms=p99,
            cpu_percent=self.cpu.read(),
            rss_mb=proc.rss_mb(),
            armed=self.armed,
            arming_required=self.arming_required,
        )
