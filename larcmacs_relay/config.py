"""Typed configuration of the relay: every setting with its default (argparse lives in __main__)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from sslnet import defaults

OutputMode = Literal["sim", "grsim", "robot-box"]
TeamColour = Literal["blue", "yellow"]


@dataclass(frozen=True)
class RelayConfig:
    """Everything the relay needs; defaults are the SSL / Touchline defaults (DESIGN.md s.2)."""

    # Multicast inputs.
    interface: str = "127.0.0.1"
    vision_group: str = defaults.VISION_GROUP
    vision_port: int = defaults.VISION_PORT_SIM
    referee_group: str = defaults.REFEREE_GROUP
    referee_port: int = defaults.REFEREE_PORT
    tracker_enabled: bool = False
    tracker_group: str = defaults.VISION_GROUP
    tracker_port: int = defaults.TRACKER_PORT

    # Native ZeroMQ endpoints (both bound by the relay).
    pub_endpoint: str = defaults.RELAY_PUB
    sub_endpoint: str = defaults.RELAY_SUB

    # Command output.
    output: OutputMode = "sim"
    sim_host: str = "127.0.0.1"
    sim_control_port: int = defaults.SIM_CONTROL_PORT
    sim_blue_port: int = defaults.SIM_BLUE_PORT
    sim_yellow_port: int = defaults.SIM_YELLOW_PORT
    grsim_port: int = defaults.GRSIM_COMMAND_PORT
    # grSim's Robots_Status (grsim output only): it sends them to the sender of the last
    # command, on these ports (0: any free port, for tests)
    grsim_status_host: str = "0.0.0.0"
    grsim_status_blue_port: int = defaults.GRSIM_STATUS_BLUE_PORT
    grsim_status_yellow_port: int = defaults.GRSIM_STATUS_YELLOW_PORT
    robot_box_host: str = "127.0.0.1"
    robot_box_port: int = defaults.ROBOT_BOX_PORT
    output_rate_hz: float = 120.0
    # a new command set goes out at once, unless the previous cycle was less than this ago
    # (then as soon as it is): the cap on the datagram rate whatever the backend sends.
    # None: half an output period (the rate per robot stays <= twice output_rate_hz)
    min_output_gap_s: float | None = None
    command_timeout_s: float = 0.100
    hold_time_s: float = 1.0
    # simulator answers with the same bytes as the last one forwarded go on at most this
    # often per team (the rest are counted, not forwarded: larcmacs_relay/feedback.py); a
    # change goes on at once. 0: every answer. The backend reads them at 50 Hz.
    feedback_interval_s: float = 0.02

    # Kick / dribbler conversions (uncalibrated, documented in README.md).
    chip_angle_deg: float = 45.0
    kick_mps_per_volt: float = 0.5  # robot-box kicker voltage byte <-> kick speed
    max_kick_mps: float = 6.5  # league limit
    dribbler_rpm_per_unit: float = 1000.0  # robot-box dribbler speed byte <-> rpm
    robot_box_charge: bool = True  # kicker-charge enable for native commands
    # real robots or an external simulator: start disarmed, send no command (only stops)
    # until an Arming message arms the relay; an e-stop press disarms it
    require_arming: bool = False

    # Seed LARCmaCS compatibility sockets.
    compat: bool = False
    compat_vision_pub: str = defaults.COMPAT_VISION_PUB
    compat_referee_pub: str = defaults.COMPAT_REFEREE_PUB
    compat_commands: str = defaults.COMPAT_COMMANDS
    our_team: TeamColour = "blue"

    stats_interval_s: float = 1.0
    log_interval_s: float = 5.0
    # an input datagram larger than this is dropped and counted "oversized" (SSL-Vision
    # detection frames are ~1-2 KB, geometry with 8 camera calibrations ~3 KB)
    max_datagram_bytes: int = 32768
    # on every shutdown it can see, a zero command this many times to every robot commanded
    last_word_repeats: int = 3
    # Referee messages from the station's internal referee ("referee-out" topic) are
    # multicast to the referee group. None: only when the interface is loopback, so a station
    # on a venue network never competes with the real game controller unless told to.
    referee_out: bool | None = None
    referee_out_ttl: int = 1
    # The backend's world estimate ("tracker-out" topic) as the league's tracked vision
    # (TrackerWrapperPacket). The game controller adopts the first tracker it hears, so by
    # default it goes out on the loopback interface only (IP_MULTICAST_IF 127.0.0.1, TTL 0),
    # to ``tracker_out_group:port``; on --interface (a venue network) only when the operator
    # gives --tracker-out (``tracker_out_lan``).
    tracker_out: bool = True
    tracker_out_group: str = defaults.VISION_GROUP
    tracker_out_port: int = defaults.TRACKER_PORT
    tracker_out_lan: bool = False
    tracker_out_ttl: int = 1

    @property
    def tracker_out_interface(self) -> str:
        """The interface tracked vision leaves on: ``interface`` only when asked for
        (--tracker-out), else loopback."""
        return self.interface if self.tracker_out_lan else "127.0.0.1"

    @property
    def tracker_out_on_loopback(self) -> bool:
        return self.tracker_out_interface.startswith("127.")

    @property
    def min_gap_s(self) -> float:
        """The least time between two output cycles: ``min_output_gap_s``, else none for a
        simulator (every command set goes out at once: latency first) and half a period for
        real robots (robot-box: a radio link takes about one datagram per period)."""
        if self.min_output_gap_s is None:
            return 0.5 / self.output_rate_hz if self.output == "robot-box" else 0.0
        return self.min_output_gap_s

    @property
    def referee_out_enabled(self) -> bool:
        if self.referee_out is None:
            return self.interface.startswith("127.")
        return self.referee_out

    def validate(self) -> None:
        """Raise ValueError for settings the relay cannot run safely with."""
        if self.output not in ("sim", "grsim", "robot-box"):
            raise ValueError(f"unknown output mode {self.output!r}")
        if self.output_rate_hz < 100.0:
            raise ValueError("output_rate_hz must be >= 100 (simulators need >= 100 Hz)")
        if self.min_output_gap_s is not None and \
                not 0.0 <= self.min_output_gap_s <= 1.0 / self.output_rate_hz:
            raise ValueError("min_output_gap_s must be in [0, 1/output_rate_hz] s")
        if not 0.0 < self.command_timeout_s <= 1.0:
            raise ValueError("command_timeout_s must be in (0, 1] s")
        if self.hold_time_s < 0.0:
            raise ValueError("hold_time_s must be >= 0")
        if not 0.0 <= self.feedback_interval_s <= 0.05:
            # a held answer goes on within two intervals; the backend trusts a robot's ball
            # contact for 0.2 s after its last answer
            raise ValueError("feedback_interval_s must be in [0, 0.05] s")
        if self.our_team not in ("blue", "yellow"):
            raise ValueError(f"our_team must be blue or yellow, not {self.our_team!r}")
        if not 0 < self.tracker_out_port < 65536:
            raise ValueError(f"tracker_out_port {self.tracker_out_port} is not a UDP port")
        if not 1 <= self.tracker_out_ttl <= 255:
            raise ValueError("tracker_out_ttl must be in 1..255")
        if self.kick_mps_per_volt <= 0 or self.dribbler_rpm_per_unit <= 0:
            raise ValueError("conversion factors must be > 0")
