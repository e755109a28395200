"""Shared by the processors: a latency stage, the rate-limited log of bad input, parsing
with a reason."""

from __future__ import annotations

import logging
import time
from collections import deque
from typing import Any

import zmq
import zmq.asyncio

from sslnet import streams
from sslnet.ratelog import RateLimitedLog
from sslnet.streams import StreamCounter
from sslpb import touchline_pb2 as tl

from ..bus import Reader
from ..processor import Processor

log = logging.getLogger("touchline.processors")
_NOBLOCK, _MORE_NOBLOCK = int(zmq.NOBLOCK), int(zmq.SNDMORE | zmq.NOBLOCK)
badlog = RateLimitedLog(log, interval_s=10.0)


class LatencyStage:
    """Milliseconds from a vision datagram's arrival at the relay to one point of the
    pipeline, over the last few hundred samples."""

    def __init__(self, maxlen: int = 500) -> None:
        self.samples: deque[float] = deque(maxlen=maxlen)

    def add_since(self, receive_time_ns: int) -> None:
        self.add_at(time.time_ns(), receive_time_ns)

    def add_at(self, now_ns: int, receive_time_ns: int) -> None:
        """``add_since`` with the time already read (``time.time_ns()``)."""
        if receive_time_ns > 0:
            self.samples.append((now_ns - receive_time_ns) / 1e6)

    def summary(self) -> dict[str, float]:
        vals = sorted(self.samples)
        if not vals:
            return {"mean_ms": 0.0, "p50_ms": 0.0, "p99_ms": 0.0, "n": 0}
        return {
            "mean_ms": sum(vals) / len(vals),
            "p50_ms": vals[len(vals) // 2],
            "p99_ms": vals[min(len(vals) - 1, int(0.99 * len(vals)))],
            "n": len(vals),
        }


def read_counting_missed(reader: Reader[tl.Envelope], counter: StreamCounter,
                         what: str) -> list[tl.Envelope]:
    """The new envelopes of ``reader``; those overwritten on the bus before it read them (a
    flood faster than the ingest decodes) are counted in ``counter`` as BEHIND, so every
    datagram the relay forwarded is counted somewhere."""
    missed = reader.missed
    envs = reader.read_new()
    if reader.missed > missed:
        n = reader.missed - missed
        counter.rate.total += n
        counter.error(streams.BEHIND, f"{n} {what} datagram(s) overwritten on the bus before "
                      "they were decoded", n=n)
        badlog.warning(f"{what}-behind", "%s ingest behind: %d datagram(s) not decoded",
                       what, n)
    return envs


class SocketProcessor(Processor):
    """A processor that talks to the relay through a ZeroMQ socket, which the station makes
    on its own loop when it starts and attaches (the processor itself is built earlier)."""

    _sock: zmq.asyncio.Socket | None = None
    _out: Any = None

    def attach(self, sock: zmq.asyncio.Socket) -> None:
        self._sock = sock
        # sends go through a plain socket on the same ZeroMQ socket: a PUB never blocks (it
        # drops at its high-water mark), so no future and no event-loop round per send
        self._out = zmq.Socket.shadow(sock.underlying) if isinstance(sock, zmq.Socket) \
            else sock
        self._direct = isinstance(self._out, zmq.Socket)

    def send(self, frames: list[bytes]) -> None:
        """Sends ``frames`` now, without waiting (a PUB socket drops what it cannot queue)."""
        if self._out is None:
            raise RuntimeError(f"{self.name}: no socket attached (the station attaches it "
                               "in start)")
        try:
            if self._direct and len(frames) == 2:
                # send_multipart's work without its checks and enum flags (an enum | int
                # builds an enum member): 0.9 us for the two parts instead of 2.5
                out = self._out
                out.send(frames[0], _MORE_NOBLOCK)
                out.send(frames[1], _NOBLOCK)
            else:
                self._out.send_multipart(frames, zmq.NOBLOCK)
        except zmq.Again:  # a full queue: like a PUB at its high-water mark, dropped
            self.dropped += 1

    dropped = 0
    _direct = False

    @property
    def attached(self) -> bool:
        return self._sock is not None

    @property
    def sock(self) -> zmq.asyncio.Socket:
        if self._sock is None:
            raise RuntimeError(f"{self.name}: no socket attached (the station attaches it "
                               "in start)")
        return self._sock
