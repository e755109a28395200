"""The robot box output (real robots): one 13-byte datagram per robot per cycle (the seed's
layout: README.md; the encoder: codecs.encode_robot_box). The datagram has no team field, so
the box drives one team only (``--our-team``): command_input.py drops the other team's
commands.
"""

from __future__ import annotations

from larcmacs_relay import codecs
from larcmacs_relay.codecs import Command
from larcmacs_relay.part import RelayPart


class RobotBoxOutput(RelayPart):
    """Each due robot's datagram to the robot box."""

    _box_host: str

    def _setup_robot_box(self) -> None:
        cfg = self.config
        self._box_host = cfg.robot_box_host
        #: robot-box output: the only team it may drive (its datagrams cannot say which)
        self._box_team = (
            (codecs.TEAM_BLUE if cfg.our_team == "blue" else codecs.TEAM_YELLOW)
            if cfg.output == "robot-box" else None)

    def _send_robot_box(self, due: list[Command]) -> None:
        cfg = self.config
        for c in due:
            self._send(
                codecs.encode_robot_box(
                    c,
                    kick_mps_per_volt=cfg.kick_mps_per_volt,
                    dribbler_rpm_per_unit=cfg.dribbler_rpm_per_unit,
                    charge=cfg.robot_box_charge,
                ),
                (self._box_host, cfg.robot_box_port),
            )
