"""``python -m fieldsim [flags]``: run the simulator until SIGINT/SIGTERM (exit 0)."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import signal
import sys
from collections.abc import Sequence

from fieldsim.config import CAMERA_PHASES, SimConfig
from fieldsim.server import FieldSim

log = logging.getLogger("fieldsim")


def _gains(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("expected comma-separated numbers") from None
    if not values or any(not v > 0 for v in values):
        raise argparse.ArgumentTypeError("gains must be positive numbers")
    return values


def _point(text: str) -> tuple[float, float]:
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError("expected X,Y in metres") from None
    return x, y


def build_parser() -> argparse.ArgumentParser:
    d = SimConfig()
    p = argparse.ArgumentParser(
        prog="python -m fieldsim",
        description="Touchline's built-in SSL simulator: vision multicast + simulation protocol.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    w = p.add_argument_group("world")
    w.add_argument("--seed", type=int, default=d.seed, help="random seed (gains, noise, faults)")
    w.add_argument("--division", choices=["A", "B"], default=d.division)
    w.add_argument("--blue", type=int, default=d.blue, help="blue robots at start (0..11)")
    w.add_argument("--yellow", type=int, default=d.yellow, help="yellow robots at start (0..11)")
    w.add_argument("--blue-positive", action="store_true",
                   help="blue starts on the positive-x half")
    w.add_argument("--generation", type=int, choices=[1, 2], default=d.generation,
                   help="1: unequal per-robot gains C, 2: C = 1")
    w.add_argument("--gain-min", type=float, default=d.gain_min)
    w.add_argument("--gain-max", type=float, default=d.gain_max)
    w.add_argument("--gains", type=_gains, default=None,
                   help="generation 1: fixed C list 'c1,c2,...' for blue 0-15 then yellow 0-15")
    w.add_argument("--physics-hz", type=float, default=d.physics_hz)
    w.add_argument("--max-accel", type=float, default=d.robot_max_accel, help="m/s^2")
    w.add_argument("--max-speed", type=float, default=d.robot_max_speed, help="m/s")
    w.add_argument("--command-timeout", type=float, default=d.command_timeout_s, help="s")
    w.add_argument("--ball-decel", type=float, default=d.ball_rolling_decel, help="m/s^2")
    w.add_argument("--chip-restitution", type=float, default=d.chip_bounce_restitution,
                   help="vertical speed kept by a chipped ball's bounce")
    w.add_argument("--other-ball", type=_point, action="append", default=[], metavar="X,Y",
                   help="leave another ball at X,Y (m): seen by the cameras, not played "
                        "(repeatable)")
    v = p.add_argument_group("vision")
    v.add_argument("--cameras", type=int, choices=[1, 2, 4, 8], default=d.cameras,
                   help="8: two rows of four along the field (division A)")
    v.add_argument("--camera-hz", type=float, default=d.camera_hz)
    v.add_argument("--camera-phases", choices=CAMERA_PHASES, default=d.camera_phases,
                   help="spread: each camera its own random phase; together: every camera "
                        "captures at once, the frames sent back to back (like grSim)")
    v.add_argument("--geometry-hz", type=float, default=d.geometry_hz)
    v.add_argument("--overlap-mm", type=float, default=d.camera_overlap_mm)
    v.add_argument("--noise-mm", type=float, default=d.noise_mm)
    v.add_argument("--noise-rad", type=float, default=d.noise_rad)
    v.add_argument("--miss-prob", type=float, default=d.miss_prob)
    v.add_argument("--false-prob", type=float, default=d.false_prob)
    n = p.add_argument_group("network")
    n.add_argument("--interface", default=d.interface, help="multicast interface address")
    n.add_argument("--vision-group", default=d.vision_group)
    n.add_argument("--vision-port", type=int, default=d.vision_port)
    n.add_argument("--vision-ttl", type=int, default=d.vision_ttl)
    n.add_argument("--sim-host", default=d.sim_host, help="address the command ports bind")
    n.add_argument("--control-port", type=int, default=d.control_port)
    n.add_argument("--blue-port", type=int, default=d.blue_port)
    n.add_argument("--yellow-port", type=int, default=d.yellow_port)
    n.add_argument("--grsim-port", type=int, default=d.grsim_port)
    n.add_argument("--grsim-status-blue-port", type=int, default=d.grsim_status_blue_port,
                   help="grSim Robots_Status (blue) to the last grSim command's sender")
    n.add_argument("--grsim-status-yellow-port", type=int, default=d.grsim_status_yellow_port)
    n.add_argument("--truth-pub", default=None, metavar="ENDPOINT",
                   help="ZeroMQ PUB endpoint for ground truth, e.g. tcp://127.0.0.1:5580")
    p.add_argument("--log-level", default="INFO")
    return p


def config_from_args(args: argparse.Namespace) -> SimConfig:
    cfg = SimConfig(
        seed=args.seed,
        division=args.division,
        blue=args.blue,
        yellow=args.yellow,
        blue_on_positive_half=args.blue_positive,
        generation=args.generation,
        gain_min=args.gain_min,
        gain_max=args.gain_max,
        gains=args.gains,
        physics_hz=args.physics_hz,
        robot_max_accel=args.max_accel,
        robot_max_speed=args.max_speed,
        command_timeout_s=args.command_timeout,
        ball_rolling_decel=args.ball_decel,
        chip_bounce_restitution=args.chip_restitution,
        other_balls=list(args.other_ball),
        cameras=args.cameras,
        camera_hz=args.camera_hz,
        camera_phases=args.camera_phases,
        geometry_hz=args.geometry_hz,
        camera_overlap_mm=args.overlap_mm,
        noise_mm=args.noise_mm,
        noise_rad=args.noise_rad,
        miss_prob=args.miss_prob,
        false_prob=args.false_prob,
        interface=args.interface,
        vision_group=args.vision_group,
        vision_port=args.vision_port,
        vision_ttl=args.vision_ttl,
        sim_host=args.sim_host,
        control_port=args.control_port,
        blue_port=args.blue_port,
        yellow_port=args.yellow_port,
        grsim_port=args.grsim_port,
        grsim_status_blue_port=args.grsim_status_blue_port,
        grsim_status_yellow_port=args.grsim_status_yellow_port,
        truth_pub=args.truth_pub,
    )
    cfg.validate()
    return cfg


async def run(config: SimConfig) -> int:
    """Run until SIGINT/SIGTERM; 0 on a clean stop, 1 if the loop failed."""
    sim = FieldSim(config)
    await sim.start()
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    waiter = asyncio.create_task(stop.wait())
    runner = asyncio.create_task(sim.wait())
    await asyncio.wait({waiter, runner}, return_when=asyncio.FIRST_COMPLETED)
    failed = runner.done() and not stop.is_set()
    waiter.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await waiter
    await sim.stop()
    runner.cancel()
    with contextlib.suppress(asyncio.CancelledError, Exception):
        await runner
    log.info("fieldsim stopped: %s", sim.status())
    return 1 if failed else 0


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=args.log_level.upper(),
                        format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    try:
        config = config_from_args(args)
    except ValueError as exc:
        parser.error(str(exc))
    try:
        return asyncio.run(run(config))
    except OSError as exc:
        log.error("fieldsim cannot start: %s", exc)
        return 2


if __name__ == "__main__":
    sys.exit(main())
