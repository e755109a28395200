"""The relay: its parts constructed and started, nothing else (each part is a module:
README.md, "Where to read").

Use ``Relay(config)`` and ``await relay.run()`` (``relay.stop()`` ends it), or
``await run_relay(config, stop_event)``. Nothing is opened before ``run()``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging

import zmq
import zmq.asyncio

from larcmacs_relay.answers import Answers
from larcmacs_relay.command_input import CommandInput
from larcmacs_relay.commands import CommandTable
from larcmacs_relay.compat_io import CompatSockets
from larcmacs_relay.config import RelayConfig
from larcmacs_relay.cycle import CommandCycle
from larcmacs_relay.grsim import GrsimOutput
from larcmacs_relay.inputs import MulticastInputs
from larcmacs_relay.part import Opened, endpoint
from larcmacs_relay.referee_out import RefereeOutput
from larcmacs_relay.robot_box import RobotBoxOutput
from larcmacs_relay.safety import SafetyLatches
from larcmacs_relay.sim_protocol import SimProtocolOutput
from larcmacs_relay.stats import Statistics
from larcmacs_relay.tracker_out import TrackerOutput
from sslnet.rate import RateCounter
from sslnet.ratelog import RateLimitedLog
from sslnet.streams import StreamCounter

log = logging.getLogger("larcmacs_relay")


class Relay(MulticastInputs, CommandInput, CompatSockets, SafetyLatches, CommandCycle,
            SimProtocolOutput, GrsimOutput, RobotBoxOutput, TrackerOutput, RefereeOutput,
            Answers, Statistics):
    """One relay instance. Attributes ``streams``, ``table`` and the bound endpoints
    (``pub_address``, ``sub_address``, ``compat_vision_address``, ``compat_referee_address``)
    are valid once ``ready`` is set."""

    def __init__(self, config: RelayConfig) -> None:
        config.validate()
        self.config = config
        self.table = CommandTable(config.command_timeout_s, config.hold_time_s)
        names = ["vision", "referee", "tracker", "commands", "output", "sim_responses"]
        names += ["sim_commands", "referee_out", "tracker_out"]
        if config.output == "grsim":
            names.append("grsim_status")
        if config.compat:
            names.append("compat_commands")
        self.streams = {n: StreamCounter(n) for n in names}
        self._output = self.streams["output"]
        self.cycles = RateCounter()
        self.ready = asyncio.Event()
        self.pub_address = ""
        self.sub_address = ""
        self._stop = asyncio.Event()
        self._ratelog = RateLimitedLog(log, config.log_interval_s)
        self._sources = {}
        self._monotonic_loop = None
        self._ctx: zmq.asyncio.Context | None = None
        self._pub = None
        self._setup_inputs()
        self._setup_command_input()
        self._setup_compat()
        self._setup_safety()
        self._setup_cycle()
        self._setup_sim_protocol()
        self._setup_robot_box()
        self._setup_tracker_out()
        self._setup_referee_out()
        self._setup_answers()
        self._setup_stats()

    def stop(self) -> None:
        self._stop.set()

    async def run(self) -> None:
        loop = asyncio.get_running_loop()
        cfg = self.config
        ctx = zmq.asyncio.Context()
        self._ctx = ctx
        opened = Opened(ctx)
        udp = opened.udp
        tasks: list[asyncio.Task[None]] = []
        sub_fd: int | None = None
        try:
            pub = opened.zsock(zmq.PUB)
            pub.setsockopt(zmq.SNDHWM, 10000)
            pub.bind(cfg.pub_endpoint)
            self.pub_address = endpoint(pub)
            self._pub = pub
            sub = opened.zsock(zmq.SUB)
            fd = self._open_command_input(sub)
            self.sub_address = endpoint(sub)
            compat_sub = self._open_compat(opened) if cfg.compat else None
            self._open_inputs(loop, udp)
            self._open_output(udp)
            self._open_answers(loop, udp)
            self._open_referee_out(udp)
            self._open_tracker_out(udp)
            sub_fd = fd
            loop.add_reader(fd, self._drain_commands, sub)
            if compat_sub is not None:
                tasks.append(asyncio.create_task(self._compat_loop(compat_sub)))
            tasks.append(asyncio.create_task(self._stats_loop()))
            log.info(
                "relay up: pub %s, sub %s, output %s at %.0f Hz",
                self.pub_address,
                self.sub_address,
                cfg.output,
                cfg.output_rate_hz,
            )
            self.ready.set()
            stop_wait = asyncio.create_task(self._stop.wait())
            done, _ = await asyncio.wait([stop_wait, *tasks], return_when=asyncio.FIRST_COMPLETED)
            stop_wait.cancel()
            for t in done:
                if t is not stop_wait and not t.cancelled() and t.exception() is not None:
                    raise t.exception()  # type: ignore[misc]
        finally:
            self._close_cycle()
            self._close_answers()
            if sub_fd is not None:
                with contextlib.suppress(Exception):
                    loop.remove_reader(sub_fd)
            for t in tasks:
                t.cancel()
            for t in tasks:
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await t
            try:
                self.last_word()
            except Exception:  # the sockets are closed all the same
                log.exception("last word failed")
            for s in udp:
                with contextlib.suppress(Exception):
                    loop.remove_reader(s.fileno())
                s.close()
            self._pub = self._compat_vision = self._compat_referee = None
            self._udp_out = None
            self._referee_out = None
            self._tracker_out = None
            for z in opened.zmq:
                z.close(linger=0)
            ctx.term()
            self._ctx = None
            log.info("relay stopped")

    async def _stats_loop(self) -> None:
        """The statistics (stats.py) on the PUB every ``stats_interval_s``."""
        while True:
            await asyncio.sleep(self.config.stats_interval_s)
            self._publish(self._pub, [b"stats", self.stats().SerializeToString()])


async def run_relay(config: RelayConfig, stop: asyncio.Event | None = None) -> None:
    """Run a relay until ``stop`` is set (or forever); all sockets are closed on return."""
    relay = Relay(config)
    if stop is None:
        await relay.run()
        return
    task = asyncio.create_task(relay.run())
    waiter = asyncio.create_task(stop.wait())
    await asyncio.wait([task, waiter], return_when=asyncio.FIRST_COMPLETED)
    relay.stop()
    waiter.cancel()
    await task
