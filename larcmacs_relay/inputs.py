"""The multicast inputs: vision, referee and (with --tracker) another tracker's tracked
vision, each datagram onto the native PUB as an Envelope, unchanged.

Vision and referee are one path (a datagram is a payload: the backend decodes it, once);
only the tracker input is checked beyond size and emptiness, and its own tracked vision
heard back on loopback is dropped here. Start at ``_drain_input``: it is the relay's hottest
loop (every camera frame), so it reads its names into locals once per wake-up.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import time
from collections.abc import Callable

import zmq

from larcmacs_relay import codecs
from larcmacs_relay.part import MAX_BATCH, MAX_DATAGRAM, NOBLOCK, RelayPart
from sslnet import streams
from sslnet.multicast import open_multicast_receiver
from sslnet.streams import StreamCounter
from sslpb import touchline_pb2

log = logging.getLogger("larcmacs_relay")

_SNDMORE_NOBLOCK = int(zmq.SNDMORE | zmq.NOBLOCK)
#: a frame sent by libzmq's binding itself: pyzmq's Socket.send is a Python layer over it (for
#: routing ids and groups, which a PUB has not), a call and keywords more per frame
_SEND_FRAME = zmq.backend.Socket.send
_TOPICS = {"vision": b"vision", "referee": b"referee", "tracker": b"tracker"}
_STREAM_IDS = {
    "vision": touchline_pb2.STREAM_VISION,
    "referee": touchline_pb2.STREAM_REFEREE,
    "tracker": touchline_pb2.STREAM_TRACKER,
}


class MulticastInputs(RelayPart):
    """Vision, referee and tracker in; envelopes out (the PUB), copies to the seed's PUBs."""

    #: each stream's last Envelope sequence (1-based per stream)
    _sequences: dict[str, int]
    #: own tracked frames heard back on the tracker input (not forwarded, not errors)
    own_tracker_echoes: int

    def _setup_inputs(self) -> None:
        self._sequences = {"vision": 0, "referee": 0, "tracker": 0}
        self.own_tracker_echoes = 0

    def _open_inputs(self, loop: asyncio.AbstractEventLoop, udp: list[socket.socket]) -> None:
        """Joins each input's group and reads it from the loop's reader."""
        cfg = self.config
        inputs: list[tuple[str, str, int, Callable[[bytes], str | None]]] = [
            ("vision", cfg.vision_group, cfg.vision_port, codecs.check_forwarded),
            ("referee", cfg.referee_group, cfg.referee_port, codecs.check_forwarded),
        ]
        if cfg.tracker_enabled:
            inputs.append(
                ("tracker", cfg.tracker_group, cfg.tracker_port, codecs.validate_tracker)
            )
        for name, group, port, validate in inputs:
            rx = open_multicast_receiver(group, port, cfg.interface)
            udp.append(rx)
            loop.add_reader(rx.fileno(), self._drain_input, rx, name, validate)
            log.info("listening for %s on %s:%d via %s", name, group, port, cfg.interface)

    def _drain_input(
        self, sock: socket.socket, name: str, validate: Callable[[bytes], str | None]
    ) -> None:
        """Read every datagram waiting on ``sock`` (never just one per wakeup); after
        MAX_BATCH in a row it yields to the loop (the reader is level-triggered and comes back
        at once), so a flood cannot starve the command output. Vision and referee are not
        decoded here (the backend decodes them once): per datagram only the size and
        emptiness checks, its receive time, one Envelope and one ZeroMQ message; the stream's
        packets are counted once per wake-up (one clock read, not one per datagram)."""
        counter = self.streams[name]
        topic = _TOPICS[name]
        stream = _STREAM_IDS[name]
        pub = self._pub
        max_bytes = self.config.max_datagram_bytes
        sources = self._sources
        seq = self._sequences[name]
        tracker = name == "tracker"
        # vision and referee: only an empty datagram is refused (check_forwarded), tested here
        forwarded = validate is codecs.check_forwarded
        compat_vision = self._compat_vision if name == "vision" else None
        compat_referee = name == "referee" and self._compat_referee is not None
        recvfrom = sock.recvfrom
        time_ns = time.time_ns
        envelope = touchline_pb2.Envelope
        send = _SEND_FRAME
        n = nbytes = 0
        try:
            for _ in range(MAX_BATCH):
                try:
                    data, addr = recvfrom(MAX_DATAGRAM)
                except (BlockingIOError, InterruptedError):
                    return
                except OSError as exc:
                    counter.error("receive failed", str(exc))
                    self._ratelog.warning(f"{name}-recv", "%s receive failed: %s", name, exc)
                    return
                receive_ns = time_ns()
                size = len(data)
                if forwarded and data and size <= max_bytes:
                    pass  # the common case: nothing more to check
                elif not self._input_ok(data, addr, name, validate, counter, tracker):
                    continue
                n += 1
                nbytes += size
                seq += 1
                source = sources.get(addr)
                if source is None:
                    source = self._source(addr)
                if pub is not None:
                    body = envelope(stream=stream, receive_time_ns=receive_ns, sequence=seq,
                                    source=source, payload=data).SerializeToString()
                    try:  # a PUB queues a multipart message whole or not at all
                        send(pub, topic, _SNDMORE_NOBLOCK)
                        send(pub, body, NOBLOCK)
                    except zmq.Again:
                        self._ratelog.warning("pub-full", "ZeroMQ PUB queue full, message "
                                              "dropped")
                if compat_vision is not None:
                    self._publish(compat_vision, [data])
                elif compat_referee:
                    self._compat_referee_out(data, addr)
        finally:
            self._sequences[name] = seq
            if n:
                counter.packets_at(n, nbytes, time.monotonic())

    def _input_ok(self, data: bytes, addr: tuple[str, int], name: str,
                  validate: Callable[[bytes], str | None], counter: StreamCounter,
                  tracker: bool) -> bool:
        """The checks of an input datagram beyond the common case (a tracker's, an own tracked
        frame heard back, an empty or oversized one): False when it is not forwarded (an echo
        is counted apart, a bad one as an error by reason, and logged)."""
        if tracker and self._own_tracker_uuids and self._own_echo(data):
            self.own_tracker_echoes += 1
            return False
        max_bytes = self.config.max_datagram_bytes
        if len(data) > max_bytes:
            reason: str | None = f"{len(data)} bytes, more than {max_bytes}"
            kind = streams.OVERSIZED
        else:
            try:
                reason = validate(data)
            except Exception as exc:  # a decoder surprise must not kill the reader
                reason = f"validation failed: {exc!r}"
            kind = codecs.classify(reason, data) if reason is not None else ""
        if reason is None:
            return True
        counter.error(kind, reason)
        self._ratelog.warning(
            f"{name}-bad",
            "dropped malformed %s datagram from %s:%d: %s",
            name,
            addr[0],
            addr[1],
            reason,
        )
        return False

    def _own_echo(self, data: bytes) -> bool:
        """True if ``data`` is tracked vision this relay sent (heard back on loopback)."""
        pkt, _ = codecs.parse_tracked_out(data)
        return pkt is not None and pkt.uuid in self._own_tracker_uuids
