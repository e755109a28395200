"""Command line: ``python -m larcmacs_relay [flags]`` (see README.md)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import dataclasses
import logging
import os
import signal
import sys
from collections.abc import Callable

from larcmacs_relay.config import RelayConfig
from larcmacs_relay.relay import run_relay


def _hostport(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host:
        raise argparse.ArgumentTypeError(f"expected host:port, got {text!r}")
    return host, int(port)


def build_parser() -> argparse.ArgumentParser:
    d = RelayConfig()
    p = argparse.ArgumentParser(
        prog="python -m larcmacs_relay",
        description="Touchline relay: SSL multicast <-> ZeroMQ, commands -> simulator/robots.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    a = p.add_argument
    a("--interface", default=d.interface, help="interface address to join multicast on")
    a(
        "--vision",
        type=_hostport,
        default=(d.vision_group, d.vision_port),
        metavar="GROUP:PORT",
        help="vision multicast (real SSL-Vision: 224.5.23.2:10006)",
    )
    a(
        "--referee",
        type=_hostport,
        default=(d.referee_group, d.referee_port),
        metavar="GROUP:PORT",
        help="referee multicast",
    )
    a(
        "--tracker",
        type=_hostport,
        default=None,
        metavar="GROUP:PORT",
        help=f"enable tracker input (e.g. {d.tracker_group}:{d.tracker_port})",
    )
    a("--pub", default=d.pub_endpoint, help="ZeroMQ PUB endpoint to bind")
    a("--sub", default=d.sub_endpoint, help="ZeroMQ SUB endpoint to bind")
    a("--output", choices=["sim", "grsim", "robot-box"], default=d.output)
    a("--sim-host", default=d.sim_host, help="simulator host (sim and grsim modes)")
    a("--sim-control-port", type=int, default=d.sim_control_port)
    a("--sim-blue-port", type=int, default=d.sim_blue_port)
    a("--sim-yellow-port", type=int, default=d.sim_yellow_port)
    a("--grsim-port", type=int, default=d.grsim_port)
    a("--grsim-status-blue-port", type=int, default=d.grsim_status_blue_port,
      help="where grSim sends the blue Robots_Status (grsim mode)")
    a("--grsim-status-yellow-port", type=int, default=d.grsim_status_yellow_port,
      help="where grSim sends the yellow Robots_Status (grsim mode)")
    a(
        "--robot-box",
        type=_hostport,
        default=(d.robot_box_host, d.robot_box_port),
        metavar="HOST:PORT",
        help="robot box address (robot-box mode)",
    )
    a("--rate", type=float, default=d.output_rate_hz, help="output rate, Hz (>= 100)")
    a("--min-gap", type=float, default=d.min_output_gap_s, metavar="SECONDS",
      help="least time between two output cycles: a new command set waits at most this "
           "(default: none for a simulator, half an output period for robot-box)")
    a("--max-datagram", type=int, default=d.max_datagram_bytes,
      help="input datagrams larger than this many bytes are dropped as oversized")
    a(
        "--command-timeout",
        type=float,
        default=d.command_timeout_s,
        help="seconds after which a robot's last command is replaced by zero velocity",
    )
    a(
        "--hold-time",
        type=float,
        default=d.hold_time_s,
        help="seconds zero velocity is sent before the relay stops sending to a robot",
    )
    a("--feedback-interval", type=float, default=d.feedback_interval_s, metavar="SECONDS",
      help="simulator answers the same as the last one forwarded go to the backend at most "
           "this often per team (counted, not each forwarded; a change goes at once); "
           "0: every answer")
    a("--chip-angle", type=float, default=d.chip_angle_deg, help="chip kick angle, degrees")
    a("--kick-mps-per-volt", type=float, default=d.kick_mps_per_volt)
    a("--dribbler-rpm-per-unit", type=float, default=d.dribbler_rpm_per_unit)
    a("--require-arming", action="store_true",
      help="start disarmed: no command leaves (only stops) until the backend arms the relay "
           "(Arming on ZeroMQ topic 'arming'); an e-stop press disarms it. The launcher "
           "passes it for real robots and external simulators")
    a("--compat", action="store_true", help="also serve the seed LARCmaCS ZeroMQ contract")
    a("--compat-vision-pub", default=d.compat_vision_pub)
    a("--compat-referee-pub", default=d.compat_referee_pub)
    a(
        "--compat-commands",
        default=d.compat_commands,
        help="strategy-bridge PUB to connect to (32x13 float64 matrix)",
    )
    a(
        "--our-team",
        choices=["blue", "yellow"],
        default=d.our_team,
        help="our colour, for the compat referee is_left",
    )
    a("--referee-out", action=argparse.BooleanOptionalAction, default=None,
      help="multicast the internal referee's messages (default: only on a loopback interface)")
    a("--tracker-out", type=_hostport, default=None, metavar="GROUP:PORT",
      help="multicast the station's tracked vision (TrackerWrapperPacket) to GROUP:PORT on "
           "--interface, e.g. 224.5.23.2:10010. Without it tracked vision goes out on the "
           "loopback interface only (TTL 0, to --tracker-out-local): the game controller "
           "adopts the first tracker it hears, so a station never publishes on a competition "
           "network unless told to")
    a("--tracker-out-local", type=_hostport, default=f"{d.tracker_out_group}:{d.tracker_out_port}",
      metavar="GROUP:PORT", help="where tracked vision goes on loopback (without --tracker-out)")
    a("--no-tracker-out", action="store_true",
      help="send no tracked vision at all, not even on loopback")
    a("--log-level", default="INFO")
    a("--event-loop", choices=["auto", "asyncio", "uvloop"], default="asyncio",
      help="uvloop needs the package (not a dependency: bench/relay_load.py measured no clear "
           "gain); auto: uvloop when it is installed")
    a("--profile", default=None, metavar="FILE",
      help="run under cProfile and write its stats to FILE on exit (for bench/ and issue 11: "
           "a profile before and after every change to the hot path)")
    return p


def config_from_args(args: argparse.Namespace) -> RelayConfig:
    cfg = RelayConfig(
        interface=args.interface,
        vision_group=args.vision[0],
        vision_port=args.vision[1],
        referee_group=args.referee[0],
        referee_port=args.referee[1],
        pub_endpoint=args.pub,
        sub_endpoint=args.sub,
        output=args.output,
        sim_host=args.sim_host,
        sim_control_port=args.sim_control_port,
        sim_blue_port=args.sim_blue_port,
        sim_yellow_port=args.sim_yellow_port,
        grsim_port=args.grsim_port,
        grsim_status_blue_port=args.grsim_status_blue_port,
        grsim_status_yellow_port=args.grsim_status_yellow_port,
        robot_box_host=args.robot_box[0],
        robot_box_port=args.robot_box[1],
        output_rate_hz=args.rate,
        min_output_gap_s=args.min_gap,
        max_datagram_bytes=args.max_datagram,
        command_timeout_s=args.command_timeout,
        hold_time_s=args.hold_time,
        feedback_interval_s=args.feedback_interval,
        chip_angle_deg=args.chip_angle,
        kick_mps_per_volt=args.kick_mps_per_volt,
        dribbler_rpm_per_unit=args.dribbler_rpm_per_unit,
        require_arming=args.require_arming,
        compat=args.compat,
        compat_vision_pub=args.compat_vision_pub,
        compat_referee_pub=args.compat_referee_pub,
        compat_commands=args.compat_commands,
        our_team=args.our_team,
        referee_out=args.referee_out,
        tracker_out=not args.no_tracker_out,
        tracker_out_group=args.tracker_out_local[0],
        tracker_out_port=args.tracker_out_local[1],
    )
    if args.tracker_out is not None:
        cfg = dataclasses.replace(cfg, tracker_out_lan=True, tracker_out_group=args.tracker_out[0],
                                  tracker_out_port=args.tracker_out[1])
    if args.tracker is not None:
        cfg = dataclasses.replace(
            cfg, tracker_enabled=True, tracker_group=args.tracker[0], tracker_port=args.tracker[1]
        )
    return cfg


async def _main(cfg: RelayConfig) -> None:
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    # every signal that ends the relay and can be caught: the relay stops through its
    # shutdown path, which sends the last word (a stop to every robot); only SIGKILL cannot
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        loop.add_signal_handler(sig, stop.set)
    await run_relay(cfg, stop)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=args.log_level.upper(),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    try:
        cfg = config_from_args(args)
        cfg.validate()
    except ValueError as exc:
        logging.getLogger("larcmacs_relay").error("bad configuration: %s", exc)
        return 2
    try:
        factory = _loop_factory(args.event_loop)
    except ImportError as exc:
        logging.getLogger("larcmacs_relay").error("--event-loop uvloop: %s", exc)
        return 2

    def run() -> None:
        with asyncio.Runner(loop_factory=factory) as runner:
            runner.run(_main(cfg))

    if args.profile:
        import cProfile
        import time

        # TOUCHLINE_PROFILE_CLOCK=cpu (bench/profile_station.py --clock cpu): CPU time, not
        # the wall clock (epoll waits and preemption after a send then cost nothing)
        cpu = os.environ.get("TOUCHLINE_PROFILE_CLOCK", "wall") == "cpu"
        prof = cProfile.Profile(time.thread_time) if cpu else cProfile.Profile()
        try:
            with contextlib.suppress(KeyboardInterrupt):
                prof.runcall(run)
        finally:
            prof.dump_stats(args.profile)
        return 0
    with contextlib.suppress(KeyboardInterrupt):
        run()
    return 0


def _loop_factory(kind: str) -> Callable[[], asyncio.AbstractEventLoop] | None:
    """The event loop to run on: None is asyncio's default."""
    if kind == "asyncio":
        return None
    try:
        import uvloop  # type: ignore[import-not-found,unused-ignore]
    except ImportError:
        if kind == "uvloop":
            raise
        return None
    logging.getLogger("larcmacs_relay").info("event loop: uvloop %s", uvloop.__version__)
    factory: Callable[[], asyncio.AbstractEventLoop] = uvloop.new_event_loop
    return factory


if __name__ == "__main__":
    sys.exit(main())
