"""Referee out: the station's internal referee ("referee-out" on the command SUB) as real
Referee multicast to the referee group, by default only on a loopback interface (a station
on a venue network never competes with the real game controller unless told to).
"""

from __future__ import annotations

import socket

from larcmacs_relay import codecs
from larcmacs_relay.part import RelayPart
from sslnet.multicast import open_multicast_sender


class RefereeOutput(RelayPart):
    """The referee multicast sender."""

    _referee_out: socket.socket | None

    def _setup_referee_out(self) -> None:
        self._referee_out = None

    def _open_referee_out(self, udp: list[socket.socket]) -> None:
        cfg = self.config
        if cfg.referee_out_enabled:
            rout = open_multicast_sender(cfg.interface, ttl=cfg.referee_out_ttl)
            udp.append(rout)
            self._referee_out = rout

    def _handle_referee_out(self, body: bytes) -> None:
        """The internal referee's messages go out as real Referee multicast."""
        cfg = self.config
        if self._referee_out is None:
            self._command_error("referee_out", "referee output is off (interface is not "
                                "loopback; start with --referee-out to allow it)")
            return
        ref, reason = codecs.parse_referee(body)
        if ref is None:
            self._command_error("referee_out", f"Referee rejected: {reason}")
            return
        self._multicast("referee_out", self._referee_out, body,
                        (cfg.referee_group, cfg.referee_port))
