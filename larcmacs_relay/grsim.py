"""The legacy grSim output: one grSim_Packet of commands per team per cycle (to
``grsim_port``), and teleports as grSim replacements. grSim's robot status (its answers):
answers.py; the encoders: codecs.py.
"""

from __future__ import annotations

import time

from larcmacs_relay import codecs
from larcmacs_relay.codecs import Command
from larcmacs_relay.part import Planned, RelayPart
from sslpb import ssl_simulation_control_pb2


class GrsimOutput(RelayPart):
    """grSim_Packet commands (a timestamp in each: nothing reused) and replacements."""

    def _grsim_plan(self, due: list[Command]) -> list[Planned]:
        """Each team's grSim_Packet of ``due`` (a timestamp in each: nothing reused)."""
        cfg = self.config
        plan: list[Planned] = []
        for team in codecs.TEAMS:
            cmds = [c for c in due if c.team == team]
            if cmds:
                data = codecs.encode_grsim_commands(
                    cmds, team == codecs.TEAM_YELLOW, time.time(), cfg.chip_angle_deg)
                plan.append((team, data, (self._sim_host, cfg.grsim_port),
                             tuple(c.id for c in cmds)))
        return plan

    def _send_grsim_replacement(self, cmd: ssl_simulation_control_pb2.SimulatorCommand) -> None:
        """A SimulatorCommand's teleports as a grSim replacement (nothing when it has none)."""
        pkt = codecs.sim_command_to_grsim(cmd)
        if pkt is not None:
            self._send(pkt, (self._sim_host, self.config.grsim_port))
