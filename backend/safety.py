"""The station's safety state, in one place: the emergency stop (pressed by an operator, or
adopted from the relay's latch), arming, and which team's robots may be commanded.

Where each is enforced: the stop is written to the ``estop`` topic (the control processor
holds every robot at zero while it is set) and latched in the relay (the command publisher
sends ``EmergencyStop``; ``adopt_relay_estop`` is its way back); the arming goes to the relay
with every command set (the publisher reads ``armed``); ``other_team_refusal`` is asked by the
routes before a command for a robot, and ``drives_other_team`` by the control processor in
every tick. What survives a restart: ``backend/estop.py`` (estop.json) and
``backend/arming.py`` (arming.json). Lives on the station thread: the routes change it
through the station's command queue."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from domain.wallclock import clock

from . import contract, topics
from .arming import ArmingStore
from .bus import DataBus
from .estop import EstopLatch
from .params.store import ParamStore
from .world.state import Team

log = logging.getLogger("touchline.station")

#: statistics older than this (the relay sends them every second) no longer tell its state
RELAY_STATS_FRESH_S = 3.0


class Safety:
    """The e-stop latch, the arming and the other-team rule of one station.

    ``replaying`` (a log is replayed: nothing is sent, arming is refused) and
    ``vision_age_s`` (by the receive clock: arming is refused without fresh vision) come from
    the replay and the control processor; ``relay_output`` and ``require_arming`` are what the
    launcher said (the relay's statistics say it too, once it runs)."""

    def __init__(self, bus: DataBus, params: ParamStore, state_dir: Path | None, *,
                 restarted: bool, require_arming: bool, relay_output: str | None,
                 replaying: Callable[[], bool], vision_age_s: Callable[[float], float]) -> None:
        self.params = params
        self.require_arming = require_arming
        self.launcher_output = relay_output
        self.replaying = replaying
        self.vision_age_s = vision_age_s
        self.estop_topic = bus.of(topics.ESTOP)
        self.relay_stats = bus.of(topics.RELAY_STATS)
        # the latched emergency stop: a persisted one is active from the first tick on
        self.latch = EstopLatch(state_dir)
        #: monotonic time of the last press (or of start-up with a persisted stop)
        self.estop_mono = time.monotonic()
        if self.latch.active:
            self.estop_topic.write(True)
        #: arming (a relay with --require-arming): the operator's, persisted; a start
        #: disarmed, a restart by the supervisor as the operator left it (backend/arming.py)
        self.arming_store = ArmingStore(state_dir, restarted)
        armed = self.arming_store.state
        if armed.armed and self.latch.active:  # the stop wins: disarmed
            armed = self.arming_store.set(False, "e-stop active at start")
        self._armed = armed.armed
        self.armed_by = armed.by
        self.armed_since = armed.since  # Unix s of the last arm or disarm (0: never)
        if self.arming_store.restored and self._armed:
            log.warning("restarted after a crash: ARMED as the operator left it (by %s at %s)",
                        armed.by or "?", clock(armed.since))

    # ---- the emergency stop ----

    @property
    def estop(self) -> bool:
        return bool(self.estop_topic.latest_value())

    def set_estop(self, active: bool, by: str = "") -> None:
        """Press (``active``) or release the emergency stop: persisted, on the bus (control
        stops every robot), and latched in or released from the relay (CommandPublisher)."""
        self.latch.set(active, by)
        self.estop_mono = time.monotonic()
        self.estop_topic.write(active)
        if active:
            self.disarm(f"e-stop ({by or '?'})")

    def adopt_relay_estop(self, by: str) -> None:
        """The relay is latched although this backend is not (its file was lost, or another
        backend pressed it): the stop is the relay's, and the station says so."""
        if not self.estop:
            log.warning("the relay's emergency stop is latched (by %s): active here too", by)
            self.set_estop(True, f"relay latch ({by or '?'})")

    def estop_by(self) -> str:
        return self.latch.state.by

    # ---- arming: a relay driving real robots or an external simulator sends nothing but
    # stops until an operator arms it (CommandPublisher repeats the state to the relay) ----

    @property
    def arming_required(self) -> bool:
        """The launcher said so (--require-arming) or the relay's stats do."""
        rs = self.relay_stats.latest_value()
        return self.require_arming or (rs is not None and bool(rs.get("arming_required")))

    @property
    def armed(self) -> bool:
        """Commands may reach the robots: armed by an operator, or no arming required."""
        return self._armed or not self.arming_required

    def operator_armed(self) -> bool:
        """What the operator decided (the relay is told this, required or not)."""
        return self._armed

    def arm_refusal(self) -> str | None:
        """Why arming is refused now, or None."""
        if self.estop:
            return "the emergency stop is active: release it first"
        if self.replaying():
            return "replaying a log: nothing is sent to robots (go back to live first)"
        age = self.vision_age_s(time.monotonic())
        stale = self.params.current.safety.vision_stale_s
        if age > stale:
            seen = "no vision yet" if age == float("inf") else f"no vision for {age:.1f} s"
            return f"vision is missing ({seen}, more than safety.vision_stale_s = {stale} s)"
        return None

    def set_armed(self, armed: bool, by: str = "") -> str | None:
        """Arm (refused with the reason, see ``arm_refusal``) or disarm (always)."""
        if not armed:
            self.disarm(by)
            return None
        why = self.arm_refusal()
        if why is not None:
            return why
        if not self._armed:
            log.warning("ARMED by %s: commands go to the robots", by or "?")
            state = self.arming_store.set(True, by)
            self._armed, self.armed_by, self.armed_since = True, by, state.since
        return None

    def disarm(self, by: str = "") -> None:
        if self._armed:
            log.warning("disarmed by %s: only stops go to the robots", by or "?")
            state = self.arming_store.set(False, by)
            self._armed, self.armed_by, self.armed_since = False, by, state.since

    # ---- which team's robots may be commanded ----

    def relay_output(self) -> str | None:
        """The relay's output: what its stats say, else what the launcher said; when they
        differ, robot-box (the one that cannot address a team) wins."""
        rs = self.relay_stats.latest_value()
        said = rs.get("output_mode") or None if rs is not None else None
        flag = self.launcher_output
        if said and flag and said != flag:
            return "robot-box" if "robot-box" in (said, flag) else said
        return said or flag

    def other_team_refusal(self, team: Team, rid: int) -> str | None:
        """Why robot ``team``/``rid`` must not be commanded, or None. Our team always may be;
        the other team only on a simulator output and with safety.other_team_in_simulator
        (robot-box datagrams have no team field: their robot 3 would be our robot 3)."""
        our = self.params.current.team.our_team
        if team == our:
            return None
        out = self.relay_output()
        if out == "robot-box":
            return (f"the relay drives real robots (robot-box), whose datagrams have no team "
                    f"field: a command for {team} {rid} would drive our ({our}) robot {rid}; "
                    f"only {our} robots can be commanded")
        if out is None:
            return (f"{team} is the other team and the relay's output is not known yet: only "
                    f"{our} robots can be commanded")
        if not self.params.current.safety.other_team_in_simulator:
            return (f"{team} is the other team: set safety.other_team_in_simulator to drive it "
                    f"in the simulator ({out})")
        return None

    def drives_other_team(self) -> bool:
        """The control loop may command the other team (a simulator, and the operator said).
        Asked in every control tick: the operator's switch first (off: no refusal message
        is built), then ``other_team_refusal``."""
        if not self.params.current.safety.other_team_in_simulator:
            return False
        other: Team = "yellow" if self.params.current.team.our_team == "blue" else "blue"
        return self.other_team_refusal(other, 0) is None

    # ---- what the page shows of it ----

    def estop_view(self) -> contract.EstopInfo:
        s = self.latch.state
        rs = self.relay_stats.latest_value()
        return {"active": self.estop, "since": s.since, "by": s.by,
                "relay_latched": None if rs is None else bool(rs.get("estop_latched"))}

    def arming_view(self) -> contract.ArmingInfo:
        rs = self.relay_stats.latest_value()
        required = self.arming_required
        return {"required": required, "armed": self.armed, "since": self.armed_since,
                "by": self.armed_by,
                "relay_armed": None if rs is None else bool(rs.get("armed", True)),
                "relay_unconfirmed": self.relay_arming_check(rs)[0],
                "refusal": self.arm_refusal() if required and not self.armed else None}

    def relay_arming_check(self, rs: dict[str, Any] | None = None) -> tuple[str | None, bool]:
        """(why the relay is not known to be armed as the station is, None when its fresh
        statistics say it is; whether the relay is alive: its fresh statistics may yet show
        the change). ``rs``: the latest statistics (read if None)."""
        if rs is None:
            rs = self.relay_stats.latest_value()
        if rs is None:
            return "no statistics from the relay yet (is it running?)", False
        age = time.monotonic() - rs["received_mono"]
        if age > RELAY_STATS_FRESH_S:
            return f"the relay's last statistics are {age:.1f} s old (is it running?)", False
        relay = bool(rs.get("armed", True))
        if relay != self.armed:
            return (f"the relay reports {'armed' if relay else 'disarmed'} "
                    f"(statistics {age:.1f} s old)"), True
        return None, True

    def warnings(self) -> list[str]:
        """Health lines: an active stop (every page says so), a relay that has not latched it
        a few seconds after the press, a latch file that could not be read or written; the
        relay's arming differing from the station's for a while, an arming file that could
        not be read or written."""
        return [*self._estop_warnings(), *self._arming_warnings()]

    def _estop_warnings(self) -> list[str]:
        out: list[str] = []
        s = self.latch.state
        if self.estop:
            when = clock(s.since) if s.since > 0 else "?"
            out.append(f"emergency stop active since {when} ({s.by or '?'}): every robot is "
                       f"held at zero until an operator releases it")
            rs = self.relay_stats.latest_value()
            if rs is not None and time.monotonic() - rs["received_mono"] < RELAY_STATS_FRESH_S \
                    and not rs.get("estop_latched") and time.monotonic() - self.estop_mono > 3.0:
                out.append("the relay has not latched the emergency stop (the backend holds "
                           "every robot at zero; a backend restart would rely on estop.json)")
        if self.latch.warning:
            out.append(self.latch.warning)
        return out

    def _arming_warnings(self) -> list[str]:
        out = [self.arming_store.warning] if self.arming_store.warning else []
        rs = self.relay_stats.latest_value()
        if rs is None or not self.arming_required \
                or time.monotonic() - rs["received_mono"] > RELAY_STATS_FRESH_S:
            return out
        if bool(rs.get("armed")) and not self.armed and time.time() - self.armed_since > 3.0:
            out.append("the relay is armed although the station is not (another backend armed "
                       "it?): it is disarmed again within 0.5 s")
        return out
