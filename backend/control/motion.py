"""The paper's two speed controllers (URoboRus 2022, section 5.2) and the proportional baseline,
behind one interface. Pure: no clock, no I/O; time advances only by ``dt_s`` given to ``step``.

A robot drives from A (its position when the target was set) to B along a straight line and
turns to the target orientation with a separate P controller. Along the line:

- ``Algorithm1``: trapezoid reference x*(t) (|x''| <= w, |x'| <= v), model x' = C u with C
  estimated online, C <- s C + (1 - s) (x - x(0)) / integral(u), and u = (x*' + K (x* - x)) / C.
- ``Algorithm2``: V = sqrt(2 a S) towards B (S the remaining distance), capped by v and changed
  by at most w dt from the last step's speed (the only state).
- ``Proportional``: the baseline proportional go-to controller of ``goto.py``, wrapped.

All three add a sideways P correction towards the line, hold still inside the position
tolerance, and pass through the same command limiter (max speed, max change of the velocity
vector per second, max angular speed), whose state survives a switch of algorithm
(``RobotMotion``), so switching never jumps the command by more than the acceleration limit.
Units: positions mm (as in ``Target`` and the world model), speeds m/s, angles rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from backend.control.goto import (
    GoToConfig,
    GoToController,
    LocalVelocity,
    Target,
    set_last_velocity,
)
from backend.control.params import (
    ALGORITHMS,
    AlgorithmName,
    ControllerParams,
    ControlSettings,
    LimitsParams,
)
from backend.control.profile import ProfilePoint, Trapezoid
from domain.angles import wrap_angle

_tuple_new = tuple.__new__

# Phase codes in telemetry()["phase"] (floats so that telemetry stays dict[str, float]).
PHASE_IDLE = 0
PHASE_ACCELERATE = 1
PHASE_CRUISE = 2
PHASE_DECELERATE = 3
PHASE_SETTLE = 4  # Algorithm 1 after T (feedback only), others: approaching without a phase
PHASE_HOLD = 5  # inside the position tolerance: commanded zero
PHASE_LOST = 6  # robot not seen: commanded zero, restart when seen again
PHASE_BLOCKED = 7  # commanded but not moving: the profile restarted this tick
PHASE_VELOCITY = 8  # a velocity order (a team play's): limited, no move of its own
PHASE_NAMES: dict[int, str] = {
    PHASE_IDLE: "idle",
    PHASE_ACCELERATE: "accelerate",
    PHASE_CRUISE: "cruise",
    PHASE_DECELERATE: "decelerate",
    PHASE_SETTLE: "settle",
    PHASE_HOLD: "hold",
    PHASE_LOST: "lost",
    PHASE_BLOCKED: "blocked",
    PHASE_VELOCITY: "velocity",
}

TELEMETRY_KEYS: tuple[str, ...] = (
    "t_s",  # s since the current move (re)started
    "ref_x_m",  # Algorithm 1: x*(t); others: equal to x_m (has_reference = 0)
    "has_reference",  # 1 for Algorithm 1
    "x_m",  # measured distance from A along the line A-B
    "path_length_m",  # |AB|
    "lateral_m",  # measured offset from the line, left of A->B positive
    "cmd_speed_mps",  # commanded speed along the line (command units, before the robot's C)
    "meas_speed_mps",  # measured speed along the line (from positions, smoothed)
    "c_estimate",  # estimated gain C (Algorithm 1 updates it; kept across moves and switches)
    "phase",  # PHASE_* code
    "heading_error_rad",
    "restarts",  # profile restarts (new target, lost, blocked) since creation
    "algorithm",  # index in ALGORITHMS
)


@dataclass(frozen=True, slots=True)
class RobotMotionState:
    """What the controller needs to know about the robot (from the world model)."""

    x_mm: float
    y_mm: float
    orientation_rad: float
    visible: bool = True


class MotionController(Protocol):
    def reset(self) -> None: ...

    def step(self, state: RobotMotionState, target: Target, dt_s: float) -> LocalVelocity: ...

    def telemetry(self) -> dict[str, float]: ...


def _clamp(v: float, lo: float, hi: float) -> float:
    return lo if v < lo else hi if v > hi else v


class LineController:
    """Shared machinery: the line A-B, restarts, lateral and heading control, the limiter."""

    algorithm: AlgorithmName = "proportional"

    _target: Target | None
    _ax: float
    _ay: float
    _bx: float
    _by: float
    _ux: float
    _uy: float
    _length: float
    _t: float
    _x: float
    _lat: float
    _prev_x: float | None
    _meas_speed: float
    _cmd_along: float
    _phase: int
    _holding: bool
    _lost: bool
    _block_t: float
    _block_px: float
    _block_py: float
    _blocked_now: bool
    _heading_err: float

    def __init__(self, params: ControllerParams | None = None) -> None:
        self.params = params if params is not None else ControllerParams()
        self.c_estimate = self.params.algorithm1.c_initial
        self.restarts = 0
        self._vx = 0.0  # last commanded field-frame velocity, m/s (limiter state)
        self._vy = 0.0
        self._clear()

    # -- public ------------------------------------------------------------------------------

    def reset(self) -> None:
        """Forget the move and command zero from here (HALT, lost vision, emergency stop).
        The estimate of C is kept: it is the robot's property. A move under way starts again
        from where the robot is when it is driven again, counted as a restart (as after it
        was lost): its line A-B is then no longer the whole way."""
        under_way = self._target is not None or self._lost
        self._vx = self._vy = 0.0
        self._clear()
        self._lost = under_way

    def set_params(self, params: ControllerParams) -> None:
        self.params = params
        p = params.algorithm1
        self.c_estimate = _clamp(self.c_estimate, p.c_min, p.c_max)

    def handover(self, other: LineController) -> None:
        """Take over a robot from another controller: its last command and C estimate."""
        self._vx, self._vy = other._vx, other._vy
        self.c_estimate = other.c_estimate
        self.restarts = other.restarts

    @property
    def last_command_mps(self) -> tuple[float, float]:
        """The last commanded field-frame velocity (m/s)."""
        return self._vx, self._vy

    def step(self, state: RobotMotionState, target: Target, dt_s: float) -> LocalVelocity:
        if not state.visible:
            # hold/zero; when seen again the move restarts from where the robot is then
            self._vx = self._vy = 0.0
            self._cmd_along = 0.0
            self._lost = True
            self._phase = PHASE_LOST
            return LocalVelocity.zero()
        return self.step_at(state.x_mm, state.y_mm, state.orientation_rad, target, dt_s)

    def step_at(self, x_mm: float, y_mm: float, heading: float, target: Target,
                dt_s: float) -> LocalVelocity:
        """``step`` for a robot seen at (``x_mm``, ``y_mm``) with ``heading`` (rad), without a
        RobotMotionState. The blocked detection, the limiter, the heading controller and the
        rotation into the robot's frame are written inline (every robot a camera saw, 600
        frames a second): the same arithmetic as their own functions, in the same order."""
        # (_clamp(dt_s, 0.0, 0.1), inline)
        dt = (0.0 if dt_s < 0.0 else 0.1 if dt_s > 0.1 else dt_s) if math.isfinite(dt_s) else 0.0
        params = self.params
        px, py = x_mm / 1000.0, y_mm / 1000.0
        if self._target is None or self._lost:
            self._start(px, py, target)
        elif target is not self._target and target != self._target:  # (same: no compare)
            moved_mm = math.hypot(target.x - self._target.x, target.y - self._target.y)
            if moved_mm == 0.0:
                self._target = target  # orientation only: no restart
            elif moved_mm <= self._retarget_mm():
                self._move_end(target)
            else:
                self._start(px, py, target)
        self._lost = False
        ux, uy = self._ux, self._uy
        rx, ry = px - self._ax, py - self._ay
        x = rx * ux + ry * uy
        lat = -rx * uy + ry * ux
        if self._prev_x is not None and dt > 0.0:
            inst = (x - self._prev_x) / dt
            self._meas_speed += 0.3 * (inst - self._meas_speed)
        self._prev_x = x
        self._x, self._lat = x, lat
        dist_b = math.hypot(self._bx - px, self._by - py)
        # blocked: commanded to move, not moving for blocked_time_s (the profile restarts)
        a1 = params.algorithm1
        self._blocked_now = False
        if (math.hypot(self._vx, self._vy) <= a1.blocked_speed_mps or self._holding
                or math.hypot(px - self._block_px, py - self._block_py) * 1000.0
                > a1.blocked_move_mm):  # not commanded to move, holding, or moving
            self._block_t = 0.0
            self._block_px, self._block_py = px, py
        else:
            self._block_t += dt
            if self._block_t > a1.blocked_time_s:
                self._block_t = 0.0
                self._block_px, self._block_py = px, py
                self._blocked_now = True
                self.restarts += 1
                self._on_blocked(px, py)
                ux, uy = self._ux, self._uy
                rx, ry = px - self._ax, py - self._ay
                x = rx * ux + ry * uy
                lat = -rx * uy + ry * ux
                self._x, self._lat, self._prev_x = x, lat, x
        lim = params.limits
        tol = lim.position_tolerance_mm / 1000.0
        if self._holding:
            if dist_b > 2.0 * tol:
                self._holding = False
        elif dist_b <= tol and self._may_hold():
            self._holding = True
        # always run the algorithm (Algorithm 1 keeps integrating u and refining C while it
        # holds: at rest the ratio distance / integral(u) is free of the latency bias)
        vx, vy = self._command(px, py, x, lat, heading, dt)
        if self._holding:
            along = self._hold_speed(dt)
            vx, vy = self._ux * along, self._uy * along
            self._phase = PHASE_HOLD
        if self._blocked_now:
            self._phase = PHASE_BLOCKED
        vx, vy = self._limit(vx, vy, lim, dt)
        self._cmd_along = vx * ux + vy * uy
        # the heading: a P controller (_clamp inline)
        if target.orientation is None:
            self._heading_err = 0.0
            omega = 0.0
        else:
            hp = params.heading
            err = wrap_angle(target.orientation - heading)
            self._heading_err = err
            if abs(err) <= hp.tolerance_rad:
                omega = 0.0
            else:
                wmax = lim.max_angular_radps
                omega = hp.kp_per_s * err
                omega = -wmax if omega < -wmax else wmax if omega > wmax else omega
        self._t += dt
        c, sn = math.cos(heading), math.sin(heading)  # global_to_local, inline
        # (the tuple made as such: without the named tuple's __new__, a Python call)
        return _tuple_new(LocalVelocity, (vx * c + vy * sn, -vx * sn + vy * c, omega))

    def step_velocity(self, heading: float, wanted: LocalVelocity,
                      dt_s: float) -> LocalVelocity:
        """A velocity order in the robot's frame (a team play's ``Velocity``) through the
        same limiter as every move: max speed, max change of the velocity vector per second,
        max angular speed. The move in progress is forgotten (a target after it starts from
        where the robot is then); the limiter's state carries on, so nothing jumps."""
        dt = (0.0 if dt_s < 0.0 else 0.1 if dt_s > 0.1 else dt_s) if math.isfinite(dt_s) \
            else 0.0
        lim = self.params.limits
        c, sn = math.cos(heading), math.sin(heading)
        fwd, left = wanted.forward_mps, wanted.left_mps
        vx, vy = fwd * c - left * sn, fwd * sn + left * c
        vx, vy = self._limit(vx, vy, lim, dt)
        wmax = lim.max_angular_radps
        omega = wanted.angular_radps
        omega = -wmax if omega < -wmax else wmax if omega > wmax else omega
        self._clear()
        self._phase = PHASE_VELOCITY
        self._cmd_along = math.hypot(vx, vy)
        return _tuple_new(LocalVelocity, (vx * c + vy * sn, -vx * sn + vy * c, omega))

    def _limit(self, vx: float, vy: float, lim: LimitsParams, dt: float) -> tuple[float, float]:
        """The limiter every command goes through (a move's and a velocity order's): max
        speed, then max change of the velocity vector per second from the last command,
        which it becomes."""
        s = math.hypot(vx, vy)
        if s > lim.max_speed_mps:
            vx, vy = vx * lim.max_speed_mps / s, vy * lim.max_speed_mps / s
        dvx, dvy = vx - self._vx, vy - self._vy
        dv = math.hypot(dvx, dvy)
        max_dv = lim.max_accel_mps2 * dt
        if dv > max_dv:
            k = max_dv / dv
            vx, vy = self._vx + dvx * k, self._vy + dvy * k
        self._vx, self._vy = vx, vy
        return vx, vy

    def telemetry(self) -> dict[str, float]:
        ref = self._reference()
        return {
            "t_s": self._t,
            "ref_x_m": ref if ref is not None else self._x,
            "has_reference": 1.0 if ref is not None else 0.0,
            "x_m": self._x,
            "path_length_m": self._length,
            "lateral_m": self._lat,
            "cmd_speed_mps": self._cmd_along,
            "meas_speed_mps": self._meas_speed,
            "c_estimate": self.c_estimate,
            "phase": float(self._phase),
            "heading_error_rad": self._heading_err,
            "restarts": float(self.restarts),
            "algorithm": float(ALGORITHMS.index(self.algorithm)),
        }

    # -- hooks for the algorithms ------------------------------------------------------------

    def _along(self, x: float, dt: float) -> float:
        """Commanded speed along the line (command units)."""
        raise NotImplementedError

    def _lateral_scale(self) -> float:
        return 1.0

    def _may_hold(self) -> bool:
        return True

    def _hold_speed(self, dt: float) -> float:
        """Speed along the line while holding inside the tolerance (zero, rate-limited by the
        algorithm where it has its own acceleration limit)."""
        return 0.0

    def _retarget_mm(self) -> float:
        return 0.0

    def _on_start(self) -> None:
        pass

    def _on_blocked(self, px: float, py: float) -> None:
        pass

    def _reference(self) -> float | None:
        return None

    def _command(
        self, px: float, py: float, x: float, lat: float, heading: float, dt: float
    ) -> tuple[float, float]:
        along = self._along(x, dt)
        lp = self.params.lateral
        side, hi = -lp.kp_per_s * lat, lp.max_mps  # (_clamp(side, -hi, hi), inline)
        side = (-hi if side < -hi else hi if side > hi else side) * self._lateral_scale()
        ux, uy = self._ux, self._uy
        return ux * along - uy * side, uy * along + ux * side

    # -- internals ---------------------------------------------------------------------------

    def _clear(self) -> None:
        self._target = None
        self._ax = self._ay = self._bx = self._by = 0.0
        self._ux, self._uy = 1.0, 0.0
        self._length = 0.0
        self._t = 0.0
        self._x = self._lat = 0.0
        self._prev_x = None
        self._meas_speed = 0.0
        self._cmd_along = 0.0
        self._phase = PHASE_IDLE
        self._holding = False
        self._lost = False
        self._block_t = 0.0
        self._block_px = self._block_py = 0.0
        self._blocked_now = False
        self._heading_err = 0.0

    def _set_line(self, bx: float, by: float) -> None:
        dx, dy = bx - self._ax, by - self._ay
        length = math.hypot(dx, dy)
        self._bx, self._by, self._length = bx, by, length
        if length > 1e-9:
            self._ux, self._uy = dx / length, dy / length

    def _start(self, px: float, py: float, target: Target) -> None:
        """New move from the current position (new target, seen again, blocked)."""
        if self._target is not None or self._lost:
            self.restarts += 1
        self._target = target
        self._ax, self._ay = px, py
        self._set_line(target.x / 1000.0, target.y / 1000.0)
        self._t = 0.0
        self._prev_x = None
        self._meas_speed = 0.0
        self._holding = False
        self._block_t = 0.0
        self._block_px, self._block_py = px, py
        # the last command, seen along the new line: Algorithm 2's "last step's speed"
        self._cmd_along = self._vx * self._ux + self._vy * self._uy
        self._on_start()

    def _move_end(self, target: Target) -> None:
        """The target moved a little: keep A and the time, move B."""
        self._target = target
        self._set_line(target.x / 1000.0, target.y / 1000.0)
        self._on_start_moved()

    def _on_start_moved(self) -> None:
        pass

class Algorithm1(LineController):
    """Trapezoid reference + online C estimate + feedback K (paper eq. 3)."""

    algorithm: AlgorithmName = "algorithm1"

    def _clear(self) -> None:
        super()._clear()
        self._profile = Trapezoid(0.0, 1.0, 1.0)
        self._ref = ProfilePoint(0.0, 0.0, 0.0)
        self._int_u = 0.0

    def _make_profile(self, v0: float) -> None:
        p = self.params.algorithm1
        self._profile = Trapezoid(self._length, p.v_mps, p.w_mps2, v0)

    def _on_start(self) -> None:
        # a robot already moving along the new line starts the profile at that speed
        v0 = max(0.0, self._cmd_along * self.c_estimate)
        self._make_profile(v0)
        self._int_u = 0.0

    def _on_start_moved(self) -> None:
        self._make_profile(self._profile.v0)

    def _on_blocked(self, px: float, py: float) -> None:
        assert self._target is not None
        self._vx = self._vy = 0.0  # the profile restarts from rest where the robot is
        target = self._target
        self.restarts -= 1  # _start counts the restart
        self._start(px, py, target)

    def _retarget_mm(self) -> float:
        return self.params.algorithm1.retarget_mm

    def _may_hold(self) -> bool:
        return self._t >= self._profile.duration

    def _lateral_scale(self) -> float:
        return 1.0 / self.c_estimate

    def _reference(self) -> float | None:
        return self._ref.pos

    def _along(self, x: float, dt: float) -> float:
        p = self.params.algorithm1
        # C = (x(t) - x(0)) / integral(u): the command sent over the last interval moved the
        # robot to x, so integrate it before using x
        self._int_u += self._cmd_along * dt
        stalled = self._block_t > 0.1
        if self._int_u >= max(p.c_min_integral_m, 1e-6) and x > 0.0 and not stalled:
            measured = _clamp(x / self._int_u, p.c_min, p.c_max)
            s = p.c_smoothing
            self.c_estimate = _clamp(s * self.c_estimate + (1.0 - s) * measured, p.c_min, p.c_max)
        ref = self._profile.sample(self._t)
        self._ref = ref
        prof = self._profile
        if self._t < prof.t_w:
            self._phase = PHASE_ACCELERATE
        elif self._t < prof.t_v:
            self._phase = PHASE_CRUISE
        elif self._t < prof.duration:
            self._phase = PHASE_DECELERATE
        else:
            self._phase = PHASE_SETTLE
        return (ref.vel + p.k_per_s * (ref.pos - x)) / self.c_estimate


class Algorithm2(LineController):
    """V = sqrt(2 a S), capped by v, changed by at most w dt from the last step's speed."""

    algorithm: AlgorithmName = "algorithm2"

    def _hold_speed(self, dt: float) -> float:
        step = self.params.algorithm2.w_mps2 * dt
        return _clamp(0.0, self._cmd_along - step, self._cmd_along + step)

    def _along(self, x: float, dt: float) -> float:
        p = self.params.algorithm2
        s = self._length - x
        v = math.copysign(math.sqrt(2.0 * p.a_mps2 * abs(s)), s)
        # (_clamp to [-v, v], then to [last - step, last + step], inline)
        hi = p.v_mps
        v = -hi if v < -hi else hi if v > hi else v
        last = self._cmd_along  # the only state: the speed sent last step
        step = p.w_mps2 * dt
        lo, hi = last - step, last + step
        v = lo if v < lo else hi if v > hi else v
        if abs(v - last) < 1e-12:
            self._phase = PHASE_CRUISE if abs(v) > 0.0 else PHASE_SETTLE
        elif abs(v) > abs(last):
            self._phase = PHASE_ACCELERATE
        else:
            self._phase = PHASE_DECELERATE
        return v


class Proportional(LineController):
    """The baseline proportional controller of goto.py, wrapped for the common interface."""

    algorithm: AlgorithmName = "proportional"

    def __init__(self, params: ControllerParams | None = None) -> None:
        super().__init__(params)
        self._goto = GoToController(self._goto_config())

    def _goto_config(self) -> GoToConfig:
        p = self.params
        return GoToConfig(
            kp_per_s=p.proportional.kp_per_s,
            max_speed_mps=p.proportional.v_mps,
            max_accel_mps2=p.proportional.w_mps2,
            kp_angle_per_s=p.heading.kp_per_s,
            max_angular_radps=p.limits.max_angular_radps,
            position_tolerance_mm=p.limits.position_tolerance_mm,
            angle_tolerance_rad=p.heading.tolerance_rad,
        )

    def set_params(self, params: ControllerParams) -> None:
        super().set_params(params)
        self._goto.config = self._goto_config()

    def _command(
        self, px: float, py: float, x: float, lat: float, heading: float, dt: float
    ) -> tuple[float, float]:
        assert self._target is not None
        set_last_velocity(self._goto, self._vx, self._vy)
        v = self._goto.step(
            px * 1000.0,
            py * 1000.0,
            heading,
            Target(self._bx * 1000.0, self._by * 1000.0, None),
            dt,
        )
        c, s = math.cos(heading), math.sin(heading)
        vx = v.forward_mps * c - v.left_mps * s
        vy = v.forward_mps * s + v.left_mps * c
        self._phase = PHASE_SETTLE if math.hypot(vx, vy) > 0.0 else PHASE_HOLD
        return vx, vy


_CLASSES: dict[AlgorithmName, type[LineController]] = {
    "algorithm1": Algorithm1,
    "algorithm2": Algorithm2,
    "proportional": Proportional,
}


def make_controller(
    algorithm: AlgorithmName, params: ControllerParams | None = None
) -> LineController:
    return _CLASSES[algorithm](params)


class RobotMotion:
    """One robot's controller; the algorithm can be switched at run time. The new algorithm
    takes over the last command (so the command changes by at most max_accel * dt) and the
    estimate of C; the move restarts from where the robot is."""

    def __init__(
        self, algorithm: AlgorithmName = "algorithm2", params: ControllerParams | None = None
    ) -> None:
        self._ctrl = make_controller(algorithm, params)

    @property
    def algorithm(self) -> AlgorithmName:
        return self._ctrl.algorithm

    @property
    def controller(self) -> LineController:
        return self._ctrl

    def configure(self, algorithm: AlgorithmName, params: ControllerParams) -> None:
        if algorithm != self._ctrl.algorithm:
            new = make_controller(algorithm, params)
            new.handover(self._ctrl)
            self._ctrl = new
        elif params is not self._ctrl.params:
            self._ctrl.set_params(params)

    def reset(self) -> None:
        self._ctrl.reset()

    def step(self, state: RobotMotionState, target: Target, dt_s: float) -> LocalVelocity:
        return self._ctrl.step(state, target, dt_s)

    def step_at(self, x_mm: float, y_mm: float, heading: float, target: Target,
                dt_s: float) -> LocalVelocity:
        """``step`` for a robot seen there (LineController.step_at)."""
        return self._ctrl.step_at(x_mm, y_mm, heading, target, dt_s)

    def step_velocity(self, heading: float, wanted: LocalVelocity,
                      dt_s: float) -> LocalVelocity:
        """A velocity order through the limiter (LineController.step_velocity)."""
        return self._ctrl.step_velocity(heading, wanted, dt_s)

    def telemetry(self) -> dict[str, float]:
        return self._ctrl.telemetry()


class MotionBank:
    """Controllers of many robots under one ``ControlSettings`` (what ControlProcessor needs).
    Keys are (team, id) with team "blue" / "yellow"."""

    def __init__(self, settings: ControlSettings | None = None) -> None:
        self.settings = settings if settings is not None else ControlSettings()
        self.robots: dict[tuple[str, int], RobotMotion] = {}

    def apply_settings(self, settings: ControlSettings) -> None:
        self.settings = settings
        for (team, rid), motion in self.robots.items():
            motion.configure(settings.algorithm_for(team, rid), settings.params_for(team, rid))

    def get(self, team: str, rid: int) -> RobotMotion:
        key = (team, rid)
        motion = self.robots.get(key)
        if motion is None:
            motion = RobotMotion(
                self.settings.algorithm_for(team, rid), self.settings.params_for(team, rid)
            )
            self.robots[key] = motion
        return motion

    def reset_all(self) -> None:
        for motion in self.robots.values():
            motion.reset()

    def telemetry(self) -> dict[str, dict[str, float]]:
        return {f"{t}/{i}": m.telemetry() for (t, i), m in sorted(self.robots.items())}
