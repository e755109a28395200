"""The seed LARCmaCS sockets (--compat): its 32x13 command matrices in (the same table, the
same latch and arming as native commands), vision unchanged and the referee as its JSON out.
The codecs are compat.py.
"""

from __future__ import annotations

import time

import zmq
import zmq.asyncio

from larcmacs_relay import codecs
from larcmacs_relay.compat import RefereeMapper, decode_command_matrix
from larcmacs_relay.part import Opened, RelayPart, endpoint


class CompatSockets(RelayPart):
    """The seed's matrices in, its vision and referee PUBs out."""

    _referee_mapper: RefereeMapper
    compat_vision_address: str
    compat_referee_address: str

    def _setup_compat(self) -> None:
        self._referee_mapper = RefereeMapper(self.config.our_team)
        self.compat_vision_address = ""
        self.compat_referee_address = ""
        self._compat_vision = None
        self._compat_referee = None

    def _open_compat(self, opened: Opened) -> zmq.asyncio.Socket:
        """Binds the seed's vision and referee PUBs, connects to its strategy bridge; returns
        the SUB the matrices come on (read by ``_compat_loop``)."""
        cfg = self.config
        cv = opened.zsock(zmq.PUB)
        cv.bind(cfg.compat_vision_pub)
        self.compat_vision_address = endpoint(cv)
        self._compat_vision = cv
        cr = opened.zsock(zmq.PUB)
        cr.bind(cfg.compat_referee_pub)
        self.compat_referee_address = endpoint(cr)
        self._compat_referee = cr
        compat_sub = opened.asock(zmq.SUB)
        compat_sub.setsockopt(zmq.SUBSCRIBE, b"")
        compat_sub.connect(cfg.compat_commands)
        return compat_sub

    def _compat_referee_out(self, data: bytes, addr: tuple[str, int]) -> None:
        ref, why = codecs.parse_referee(data)
        if ref is not None:
            self._publish(self._compat_referee, [self._referee_mapper.encode(ref)])
        else:
            self._ratelog.warning("compat-referee", "Referee from %s:%d not re-encoded "
                                  "for the compat output: %s", addr[0], addr[1], why)

    async def _compat_loop(self, sub: zmq.asyncio.Socket) -> None:
        cfg = self.config
        counter = self.streams["compat_commands"]
        while True:
            frames = await sub.recv_multipart()
            now = time.monotonic()
            body = frames[-1]
            try:
                result = decode_command_matrix(
                    body,
                    kick_mps_per_volt=cfg.kick_mps_per_volt,
                    max_kick_mps=cfg.max_kick_mps,
                    dribbler_rpm_per_unit=cfg.dribbler_rpm_per_unit,
                )
            except ValueError as exc:
                self._command_error("compat_commands", str(exc))
                continue
            counter.packet(len(body), now)
            for err in result.errors:
                self._command_error("compat_commands", err)
            if self.estop_latched:  # the latch holds for the seed's commands too
                self.table.stop_all(now)
                continue
            if not self.armed:
                if result.commands:
                    self._command_error("compat_commands", "relay disarmed: commands dropped",
                                        "disarmed")
                continue
            for c in result.commands:
                self.table.update(c, now)
            if result.commands:
                self._kick_output()
