"""Tracked vision out: the station's world estimate ("tracker-out" on the command SUB) as the
league's TrackerWrapperPacket multicast, checked before it goes (a bad one is counted by
reason, never sent). Safe by default: loopback only (TTL 0) unless --tracker-out
(README.md, "Tracked vision out").
"""

from __future__ import annotations

import logging
import socket

from larcmacs_relay import codecs
from larcmacs_relay.part import RelayPart
from sslnet import streams
from sslnet.multicast import open_multicast_sender

log = logging.getLogger("larcmacs_relay")


class TrackerOutput(RelayPart):
    """The tracked vision multicast; the uuids it sent (inputs.py drops their echoes)."""

    _tracker_out: socket.socket | None

    def _setup_tracker_out(self) -> None:
        self._tracker_out = None
        #: uuids of the tracked vision this relay sent: its own frames heard back on the
        #: tracker input (same group and port, loopback) are not taken as another tracker's
        self._own_tracker_uuids = set()

    def _open_tracker_out(self, udp: list[socket.socket]) -> None:
        cfg = self.config
        if not cfg.tracker_out:
            return
        # loopback: TTL 0, it cannot leave this host whatever the routes say
        tout = open_multicast_sender(
            cfg.tracker_out_interface,
            ttl=0 if cfg.tracker_out_on_loopback else cfg.tracker_out_ttl)
        udp.append(tout)
        self._tracker_out = tout
        log.info("tracked vision out to %s:%d via %s%s", cfg.tracker_out_group,
                 cfg.tracker_out_port, cfg.tracker_out_interface,
                 " (loopback only: --tracker-out to publish on --interface)"
                 if cfg.tracker_out_on_loopback else " (the venue network)")

    def _handle_tracker_out(self, body: bytes) -> None:
        """The station's world estimate goes out as the league's tracked vision, checked
        first (a bad one is counted by reason and never sent)."""
        cfg = self.config
        if self._tracker_out is None:
            self._command_error("tracker_out", "tracked vision output is off (--no-tracker-out)",
                                "output off")
            return
        pkt, reason = codecs.parse_tracked_out(body)
        if pkt is None:
            assert reason is not None
            self._command_error("tracker_out", reason, codecs.classify(reason, body))
            return
        if len(body) > cfg.max_datagram_bytes:
            self._command_error("tracker_out", f"{len(body)} bytes, more than "
                                f"{cfg.max_datagram_bytes}", streams.OVERSIZED)
            return
        if pkt.uuid not in self._own_tracker_uuids and len(self._own_tracker_uuids) < 64:
            self._own_tracker_uuids.add(pkt.uuid)
        self._multicast("tracker_out", self._tracker_out, body,
                        (cfg.tracker_out_group, cfg.tracker_out_port), "send failed")
