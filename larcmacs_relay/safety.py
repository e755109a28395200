"""The safety latches: the emergency stop, the arming, and the last word.

**Where the e-stop is latched**: ``_handle_estop`` below. A PRESS latches it (every robot
zeroed at once, the relay disarmed when arming is required); only an explicit RELEASE
unlatches it. While it is latched (or the relay is disarmed) command_input.py and
compat_io.py drop what arrives, and cycle.py's ``output_cycle`` sends only zeros whatever is
due (the last guard, where every command path meets). The last word: a stop to every robot
ever commanded on every shutdown the relay can see.
"""

from __future__ import annotations

import logging
import time

from larcmacs_relay.part import RelayPart
from sslpb import touchline_pb2

log = logging.getLogger("larcmacs_relay")


class SafetyLatches(RelayPart):
    """The e-stop latch, the arming and the last word (the state: part.py)."""

    def _setup_safety(self) -> None:
        #: the emergency stop, latched until an explicit release (EmergencyStop on "estop")
        self.estop_latched = False
        self.estop_by = ""
        #: --require-arming: disarmed until an Arming message arms it (a restart disarms)
        self.arming_required = self.config.require_arming
        self.armed = not self.config.require_arming
        self.armed_by = ""

    def _handle_estop(self, body: bytes, now: float) -> None:
        msg = touchline_pb2.EmergencyStop()
        if not self._parse("commands", msg, body):
            return
        if msg.action == touchline_pb2.EmergencyStop.PRESS:
            if not self.estop_latched:
                log.warning("emergency stop latched (by %s): zeros to every robot until an "
                            "explicit release", msg.by or "?")
            self.estop_latched, self.estop_by = True, msg.by
            if self.arming_required and self.armed:
                log.warning("disarmed by the emergency stop")
            self.armed = not self.arming_required  # the e-stop disarms
            self.table.stop_all(now)
            self._commands_changed = True
        elif msg.action == touchline_pb2.EmergencyStop.RELEASE:
            if self.estop_latched:
                log.warning("emergency stop released (by %s)", msg.by or "?")
            self.estop_latched, self.estop_by = False, ""
        else:
            self._command_error("commands", f"EmergencyStop with action {msg.action}",
                                "bad command")

    def _handle_arming(self, body: bytes, now: float) -> None:
        msg = touchline_pb2.Arming()
        if not self._parse("commands", msg, body):
            return
        if not self.arming_required:
            return  # always armed: nothing to do
        if msg.armed:
            if self.estop_latched:
                self._command_error("commands", "arming refused: the emergency stop is latched",
                                    "arming refused")
                return
            was = self.armed
            if not was:
                log.warning("ARMED (by %s): commands go to the robots", msg.by or "?")
            self.armed, self.armed_by = True, msg.by
            if not was:
                self._acknowledge()
            return
        if not self.armed:
            return  # repeated every 0.5 s: zeros for the hold time, then silence
        log.warning("disarmed (by %s): only stops go to the robots", msg.by or "?")
        self.armed, self.armed_by = False, msg.by
        self.table.stop_all(now)
        self._commands_changed = True
        self._acknowledge()

    def _acknowledge(self) -> None:
        """The statistics at once after an arming change (not a second later on the stats
        timer): the backend waits for them to tell the operator what the relay did."""
        self._publish(self._pub, [b"stats", self.stats().SerializeToString()])

    def last_word(self) -> None:
        """On every shutdown the relay can see (SIGTERM, SIGINT, an exception): zero velocity,
        no kick, dribbler off to every robot it ever commanded, ``last_word_repeats`` times
        (UDP can drop one), so the robots' last datagram from it is a stop. Only a SIGKILL
        (or a power cut) leaves the stop to the robots' own command timeout."""
        zeros = self.table.all_zero()
        if not zeros or self._udp_out is None:
            return
        for k in range(self.config.last_word_repeats):
            if k:
                time.sleep(0.005)
            self._send_commands(zeros)
        log.warning("last word: stop sent to %d robots (%d times)", len(zeros),
                    self.config.last_word_repeats)
