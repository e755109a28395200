"""The SSL simulation protocol output: each team's RobotControl per cycle (to the simulator's
blue and yellow ports), and the SimulatorCommand (teleports) to its control port. Byte
layouts: README.md, "Output modes"; the encoders: codecs.py. What the simulator answers:
answers.py.
"""

from __future__ import annotations

from larcmacs_relay import codecs
from larcmacs_relay.codecs import Command
from larcmacs_relay.part import Planned, RelayPart
from sslnet import streams
from sslpb import ssl_simulation_control_pb2


class SimProtocolOutput(RelayPart):
    """RobotControl datagrams (a team's bytes reused while its commands are the same) and
    the simulator commands."""

    #: per team, the robots' commands of the last sim datagram, its bytes, the robots'
    #: ids and each one's encoded part: a cycle with the same command objects sends the
    #: same bytes, and a robot's part is kept while its command is the same object
    _sim_out: dict[int, tuple[tuple[Command, ...], bytes, tuple[int, ...], list[bytes]]]

    def _setup_sim_protocol(self) -> None:
        self._sim_out = {}

    def _sim_plan(self, due: list[Command]) -> list[Planned]:
        """Each team's RobotControl datagram of ``due`` (sorted by team, id), its address and
        its robots' ids; a team's bytes are reused while its commands are the same objects."""
        cfg = self.config
        encode = codecs.encode_sim_robot_command
        angle = cfg.chip_angle_deg
        plan: list[Planned] = []
        blue = [c for c in due if c.team == codecs.TEAM_BLUE]
        yellow = [c for c in due if c.team != codecs.TEAM_BLUE] if len(blue) < len(due) else []
        for team, cmds, port in ((codecs.TEAM_BLUE, blue, cfg.sim_blue_port),
                                 (codecs.TEAM_YELLOW, yellow, cfg.sim_yellow_port)):
            if not cmds:
                continue
            robots = tuple(cmds)
            last = self._sim_out.get(team)
            if last is not None and last[0] == robots:  # the same objects (or equal ones)
                data, ids = last[1], last[2]
            else:
                if last is not None and len(last[0]) == len(robots):
                    parts = [p if c is o else encode(c, angle)
                             for c, o, p in zip(robots, last[0], last[3], strict=True)]
                else:
                    parts = [encode(c, angle) for c in robots]
                data = b"".join(parts)
                ids = tuple([c.id for c in robots])
                if last is not None and last[2] == ids:
                    ids = last[2]  # the same robots: the sent log sees it by identity
                self._sim_out[team] = (robots, data, ids, parts)
            plan.append((team, data, (self._sim_host, port), ids))
        return plan

    def _handle_sim_command(self, body: bytes) -> None:
        cfg = self.config
        counter = self.streams["sim_commands"]
        cmd = ssl_simulation_control_pb2.SimulatorCommand()
        if not self._parse("sim_commands", cmd, body):
            return
        if not cmd.IsInitialized():
            self._command_error("sim_commands", "SimulatorCommand misses required fields",
                                streams.MISSING_FIELD)
            return
        counter.packet(len(body))
        if cfg.output == "sim":
            self._send(body, (self._sim_host, cfg.sim_control_port))
        elif cfg.output == "grsim":
            self._send_grsim_replacement(cmd)
        else:
            self._command_error("sim_commands", "simulator commands unsupported in robot-box mode")
