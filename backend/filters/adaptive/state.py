"""The adaptive filter's state and what is read from it: the parameters a step uses, the
state list (its layout below), starting and forgetting a track, and the outputs (estimate,
velocity, prediction). The step that changes the state is ``step.py``; what becomes of a
measurement outside the gates is ``outliers.py``.

The state is one list of floats, unpacked at the start of a step and replaced by a new list at
its end: one bytecode instead of twenty attribute reads, and the list before the step is kept
as it is, so ``revise`` (a second camera at the same instant) costs nothing until it is used.
"""

from __future__ import annotations

import math
from typing import Any

from ..params import AdaptiveParams, FilterKind

Vec = tuple[float, float]

# the state list: times, model probability of "still", noise estimates, then both models
# (still: x, y and the variance of each; moving: x, y, vx, vy and the covariance [[p, b], [b, c]]
# of each axis: the noise is isotropic, so the axes share their covariances; only the mixing
# spreads differ between the axes, and they are averaged), then the bias test's running means,
# then the output (the mix of both models, kept: it is read far more often than it changes)
# t ta mu r q age rho | sx sy sp | mp mx my mvx mvy mb mc | ux uy | ex ey
# then (2-D only) the cruise model and the output velocity:
# cx cy cvx cvy ca cb cc | lam (probability of cruise against moving; < 0: it rests until -lam)
# (the 1-D state stops after ex ey; its y entries are 0)
_MU, _R, _Q, _RHO = 2, 3, 4, 6


def _velocity(S: list[float]) -> Vec:
    """The output velocity of a 2-D state: the moving models' mix, times P(not still)."""
    w = 1.0 - S[2]
    lam = S[28]
    if lam <= 0.0:  # the cruise model rests
        return (w * S[13], w * S[14])
    lm = 1.0 - lam
    return (w * (lam * S[23] + lm * S[13]), w * (lam * S[24] + lm * S[14]))


class AdaptiveState:
    """The parameters, the state and the outputs of the adaptive filter (``AdaptiveIMM``:
    the step, ``step.py``; the outlier logic, ``outliers.py``)."""

    __slots__ = (
        "S",
        "_backup",
        "_book",
        "_far",
        "_h",
        "_k",
        "_pend",
        "_prev",
        "_pri",
        "_pri_h",
        "_pure",
        "_two",
        "_vheld",
        "c_rest",
        "clutter",
        "gap_s",
        "gate2",
        "horizon",
        "kind",
        "max_speed",
        "max_speed2",
        "q0",
        "q_c",
        "q_down",
        "q_max",
        "q_min",
        "q_rate",
        "q_s",
        "r0",
        "r_max",
        "r_min",
        "rejected",
        "rho_accept",
        "rho_keep",
        "switch_c",
        "switch_ms",
        "switch_sm",
    )

    dims = 2

    def __init__(self, params: AdaptiveParams | None = None, angle: bool = False) -> None:
        p = params or AdaptiveParams()
        self.kind: FilterKind = "adaptive"
        if angle:
            r0, rmin, rmax = p.angle_init_noise_rad, p.angle_min_noise_rad, p.angle_max_noise_rad
            q0, qmin, qmax = (p.angle_accel_init_rad_s2, p.angle_accel_min_rad_s2,
                              p.angle_accel_max_rad_s2)
            self.q_s = p.angle_still_drift_rad_s ** 2
            self.max_speed = p.angle_max_rate_rad_s
        else:
            r0, rmin, rmax = p.init_noise_mm, p.min_noise_mm, p.max_noise_mm
            q0, qmin, qmax = p.accel_init_mm_s2, p.accel_min_mm_s2, p.accel_max_mm_s2
            self.q_s = p.still_drift_mm_s ** 2
            self.max_speed = p.max_speed_mm_s
        self.r0 = r0 * r0
        # a velocity estimate beyond this (the top speed + a margin for the estimate's own
        # noise) is impossible: with outliers seen, the measurement that makes it is false
        self.max_speed2 = (1.2 * self.max_speed) ** 2
        self.r_min, self.r_max = rmin * rmin, rmax * rmax
        self.q0 = q0 * q0
        self.q_min, self.q_max = qmin * qmin, qmax * qmax
        self.q_rate = p.accel_adapt_rate
        self.q_down = 1.0 + p.accel_shrink_bias
        self.gate2 = p.gate_sigma ** 2
        self.gap_s = p.gap_s
        self.horizon = float(p.noise_horizon)
        self.rho_keep = 1.0 - 1.0 / self.horizon  # the outlier rate's decay per accepted one
        self.switch_sm = p.still_to_moving_per_s
        self.switch_ms = p.moving_to_still_per_s
        self.rho_accept = p.outlier_rate_trust
        self.q_c = p.cruise_accel_mm_s2 ** 2  # (the 1-D filter has no cruise model)
        self.switch_c = p.cruise_switch_per_s
        self.c_rest = p.cruise_rest_s
        # 2 pi x the density of false detections (per unit area, spread over a disc)
        self.clutter = 2.0 / (p.outlier_spread_mm ** 2)
        self.rejected = 0
        #: the 2-D step (x and y, the cruise model) or the 1-D one (x alone): where their
        #: arithmetic differs (step.py)
        self._two = self.dims == 2
        # the constants a step reads, in one tuple (one attribute read instead of fourteen)
        self._k = (self.gap_s, self.q_rate, self.q_down, self.q_min, self.q_max, self.horizon,
                   self.r_min, self.r_max, self.switch_sm, self.switch_ms, self.q_s, self.gate2,
                   self.clutter, self.rho_keep, self.q_c, self.switch_c)
        self.S: list[float] = []  # empty: nothing measured yet
        self._h: tuple[float, ...] = ()  # the last two measurements used (t, x, y, t, x, y)
        self._pend: tuple[float, float, float] | None = None  # a reachable jump (t, x, y)
        #: the velocity reported instead of the state's for one step (see _speed_up)
        self._vheld: Vec | None = None
        # recent rejected measurements (t, x, y), the last 0.3 s: a lost track is re-acquired
        # on three of them that lie on one line
        self._far: tuple[tuple[float, float, float], ...] | None = None
        self._backup: tuple[object, ...] | None = None  # the track before a jump
        self._prev: tuple[object, ...] | None = None  # the state before the last update
        self._pri: tuple[Any, ...] | None = None  # the last step's predictions (revise)
        self._book: tuple[float, ...] | None = None  # the last measurement used, to learn from
        self._pri_h: tuple[float, ...] = ()  # _h when the predictions were made
        #: the state is what the last correction made of the last step's predictions, nothing
        #: else happened since (revise: the state before the step need not be restored unless
        #: the measurement is rejected)
        self._pure = False

    # -- the step (step.py) ------------------------------------------------------------------

    def update(self, t: float, zx: float, zy: float) -> Vec:
        raise NotImplementedError

    def revise(self, zx: float, zy: float, pri: tuple[Any, ...] | None = None) -> Vec:
        raise NotImplementedError

    # -- state -------------------------------------------------------------------------------

    @property
    def t_last(self) -> float | None:
        return self.S[0] if self.S else None

    @property
    def mu(self) -> float:
        """Probability that the object is still."""
        return self.S[_MU] if self.S else 0.5

    @property
    def r(self) -> float:
        """Estimated measurement noise variance."""
        return self.S[_R] if self.S else self.r0

    @property
    def q_m(self) -> float:
        """Estimated white-acceleration variance of the moving model."""
        return self.S[_Q] if self.S else self.q0

    @property
    def outlier_rate(self) -> float:
        return self.S[_RHO] if self.S else 0.0

    def noise(self) -> float:
        """The estimated measurement noise (std, units of the measurement)."""
        return math.sqrt(self.r)

    def reset(self) -> None:
        """Forget the object; the noise estimates are kept (they describe the camera)."""
        if self.S:
            self.r0, self.q0 = self.S[_R], self.S[_Q]
        self.S = []
        self._prev = self._pend = self._far = self._backup = self._pri = self._book = None
        self._vheld = None
        self._pure = False
        self._h = ()

    def _save(self) -> tuple[object, ...]:
        return (self.S, self._h, self._pend, self._far, self._backup, self._book)

    def _load(self, st: tuple[object, ...]) -> None:
        (self.S, self._h, self._pend, self._far, self._backup, self._book) = st  # type: ignore

    def _init(self, t: float, x: float, y: float, v: Vec = (0.0, 0.0), mu: float = 0.5,
              pvv: float | None = None) -> Vec:
        S = self.S
        if S:
            r, q, age, rho = S[_R], S[_Q], S[5], S[_RHO]
        else:
            r, q, age, rho = self.r0, self.q0, 0.0, 0.0
        pv = pvv if pvv is not None else self.max_speed ** 2 / 4
        self.S = [t, t, mu, r, q, age, rho, x, y, r, r, x, y, v[0], v[1], 0.0, pv, 0.0, 0.0, x, y,
                  x, y, v[0], v[1], r, 0.0, pv, 0.5]
        self._h = (t, x, y)
        self._pend = self._far = self._backup = self._book = None
        return (x, y)

    def _redo(self, x: float, y: float) -> Vec:
        """A revise without the last step's predictions (after a jump, or none yet): the
        step again from the state before it."""
        self._vheld = None
        if self._prev is None or not self.S:
            return self.update(self.S[0] if self.S else 0.0, x, y)
        t = self.S[0]
        self._load(self._prev)  # (the step keeps it as it is)
        return self.update(t, x, y)

    def _restore(self) -> None:
        """The state before the last step, except what the step did before its predictions
        (it had learnt from its book): what a revise corrects."""
        self.S, _, self._pend, self._far, self._backup, _ = self._prev  # type: ignore
        self._book, self._h = None, self._pri_h
        self._vheld = None
        self._pure = False

    # -- output ------------------------------------------------------------------------------

    def estimate_fast(self) -> Vec:
        S = self.S
        return (S[19], S[20])

    def estimate(self) -> Vec | None:
        S = self.S
        return (S[19], S[20]) if S else None

    def velocity(self) -> Vec:
        """The velocity; after a jump not yet confirmed, the velocity before it (one noise
        spike must not read as a 5 m/s kick: the next measurement tells)."""
        if self._vheld is not None:
            return self._vheld
        bk = self._backup
        S: list[float] = self.S if bk is None else bk[0]  # type: ignore[assignment]
        if not S:
            return (0.0, 0.0)
        return _velocity(S)

    def predict(self, t_s: float) -> Vec | None:
        S = self.S
        if not S:
            return None
        bk = self._backup
        # held on the old track (a line not yet confirmed, see _rejected): its velocity
        vx, vy = _velocity(bk[0] if bk is not None and S[19] != S[11] else S)  # type: ignore
        d = t_s - S[0]
        return (S[19] + d * vx, S[20] + d * vy)
