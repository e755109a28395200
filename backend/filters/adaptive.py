"""The default filter: a still/moving interacting multiple model that learns its noise.

Why this design (docs/experiments/filters/README.md has the numbers): a Kalman filter tuned for
one noise level is wrong at the others (3 mm assumed, 20 mm real: worse than no filter), and the
paper's filter is precise on a still object but lags a moving one. No single (q, r) pair fits a
resting ball and a kicked one, so this filter carries two motion models and lets the data pick:

* **still**: the position is constant (a tiny random walk); its estimate is the running mean,
  the most precise thing a still object allows, and its velocity is exactly zero;
* **moving**: constant velocity with white acceleration (a robot driving, a rolling ball).

They are mixed as an IMM (Blom & Bar-Shalom): per step the model probabilities follow a Markov
chain, each model starts from the mix of both, and the output is the probability-weighted
combination. Measurement noise ``r`` is estimated from the data: the innovations of accepted
measurements, minus the model's own prediction variance, averaged over a sliding horizon (the
Mehra / Sage-Husa estimator); the outlier rate is estimated the same way from the gate's verdicts.

Beside the moving model (2-D only) runs a **cruise** model: constant velocity with a small *fixed*
q (``cruise_accel_mm_s2``, the straight run's). Why: the moving model's q is estimated, and an
estimate raised by a maneuver, or by a noise sequence that looks like one (one 4-sigma
measurement at 20 mm noise sets q to its bound; the start of a track with r not yet learnt drives
it up for a second), decays only over a second or so; on a straight run the estimate meanwhile
follows the noise (the constant-speed cells at 20 mm, 1.10-1.125 x the oracle on seeds 7, 11,
2022 with 40 runs). The two are weighed by their likelihood ratio (a two-state Markov chain,
``cruise_switch_per_s``): on a straight run the cruise model's narrower prediction wins and the
estimate keeps its low-q smoothness whatever q does; at a bounce its innovations explode, it is
ruled out within a frame or two and the adaptive q carries the estimate. It is not mixed with
the moving model (a three-model IMM's mixing would cost more than the model); once all but ruled out
(probability 1e-3) it rests for ``cruise_rest_s`` (0.1 s: the moving model alone, a turning
robot does not pay for it every step) and restarts from the moving model's state, which is what
the mixing would do then. The moving model's q learns from its own innovations as before. Cost:
2.8 -> 3.6 us per 2-D step, +9 to +12 us per world-model frame of 22 robots and a ball
(bench/world_bench.py: about 103 us against Kalman's 94 then; 83 against 56 since the revise
below and the world model's cheaper merge, docs/experiments/filters/README.md).

Outliers and maneuvers (a kick, a bounce) both show up as a measurement far outside the gate. They
are told apart by physics and by the data: a measurement farther than the object could have
travelled (``max_speed``) is an outlier; a reachable one is a maneuver at once when no outliers
have been seen lately, otherwise when the next measurement confirms it (one frame of delay, only
in outlier-ridden data). A measurement only a little outside the gate, with no outliers about,
is neither: the motion changed more than q allows (a ball slowing down), and q is raised and the
step redone rather than the track restarted. A run of consistent far measurements (the ball
placed elsewhere) re-initialises the filter.

Plain float arithmetic per axis (no numpy): for a 2-state filter CPython's float operations are
several times faster than small matrices, and this runs for every object in every camera frame.
The state is one list of floats, unpacked at the start of a step and replaced by a new list at
its end: one bytecode instead of twenty attribute reads, and the list before the step is kept
as it is, so ``revise`` (a second camera at the same instant) costs nothing until it is used.
``revise`` is the correction itself (``update`` passes it its predictions: a call costs about a
tenth of the correction) and, right after an accepted correction, does not restore the state
before the step (the correction overwrites all of it; a rejected measurement restores it
first): with eight cameras a robot is revised about five times per step.
"""

from __future__ import annotations

import math
from typing import Any

from .params import AdaptiveParams, FilterKind

Vec = tuple[float, float]
#: (module globals: one lookup fewer than ``math.exp`` in the per-frame path)
_exp, _sqrt, _log = math.exp, math.sqrt, math.log

# the state list: times, model probability of "still", noise estimates, then both models
# (still: x, y and the variance of each; moving: x, y, vx, vy and the covariance [[p, b], [b, c]]
# of each axis: the noise is isotropic, so the axes share their covariances; only the mixing
# spreads differ between the axes, and they are averaged), then the bias test's running means,
# then the output (the mix of both models, kept: it is read far more often than it changes)
# t ta mu r q age rho | sx sy sp | mp mx my mvx mvy mb mc | ux uy | ex ey
# then (2-D only) the cruise model and the output velocity:
# cx cy cvx cvy ca cb cc | lam (probability of cruise against moving; < 0: it rests until -lam)
_MU, _R, _Q, _RHO = 2, 3, 4, 6
#: weight of a new normalised innovation in its running mean (the bias test)
#: (0.15, about 7 steps: round 3, from 0.1; with a lag past the gate now raising q at once, the
#: test's job is the lag building up before it, and a shorter window sees it sooner)
BIAS_A = 0.15
#: 1 / (2 x the variance of that running mean for unit white noise)
BIAS_K = (2.0 - BIAS_A) / BIAS_A / 2.0
#: below this probability the cruise model is ruled out (it rests, then restarts)
_C_FLOOR = 1e-3


def _velocity(S: list[float]) -> Vec:
    """The output velocity of a 2-D state: the moving models' mix, times P(not still)."""
    w = 1.0 - S[2]
    lam = S[28]
    if lam <= 0.0:  # the cruise model rests
        return (w * S[13], w * S[14])
    lm = 1.0 - lam
    return (w * (lam * S[23] + lm * S[13]), w * (lam * S[24] + lm * S[14]))


class AdaptiveIMM:
    """Still/moving IMM with estimated noise and robust gating (see the module doc), 2-D."""

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

    # -- the step ----------------------------------------------------------------------------

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

    def update(self, t: float, zx: float, zy: float) -> Vec:
        self._prev = (self.S, self._h, self._pend, self._far, self._backup, self._book)
        self._vheld = None
        self._pure = False
        (gap_s, q_rate, q_down, q_min, q_max, horizon, r_min, r_max, switch_sm, switch_ms, q_s,
         gate2, clutter, rho_keep, q_c, switch_c) = self._k
        cache = self._backup is None  # (after a jump, revise takes the long way)
        if not cache and self._after_jump(t, zx, zy):
            self.rejected += 1
            return self.predict(t) or (zx, zy)
        S = self.S
        if not S or t - S[0] > gap_s:
            return self._init(t, zx, zy)
        (t0, ta, ms, r, q, age, rho, sx, sy, sp, mp, mx, my, mvx, mvy, mb, mc, ux, uy, _, _,
         cx, cy, cvx, cvy, ca, cb, cc, lam) = S
        bk = self._book
        if bk is not None:  # learn from the last measurement used (once per instant)
            self._book = None
            bt, bx, by, d2m, nmx, nmy, w = bk
            # process noise: grows when the moving model's innovations exceed what it predicts
            # (normalised innovation squared > 1) or keep one sign (an acceleration the model
            # does not have: the running mean of the normalised innovations, squared over its
            # variance, is ~1 when unbiased); shrinks slowly otherwise: the smallest q the data
            # agree with
            ux += BIAS_A * (nmx * w - ux)
            uy += BIAS_A * (nmy * w - uy)
            e = 0.5 * (0.5 * d2m + (ux * ux + uy * uy) * BIAS_K)
            e = q_rate * ((e if e < 6.0 else 6.0) - q_down)
            q *= 1.0 + e + 0.5 * e * e  # ~exp(e), |e| < 1.5
            q = q_min if q < q_min else (q_max if q > q_max else q)
            # measurement noise from the second differences of the measurements used
            # (independent of the motion model, so a wrong q does not leak into r): z_k - z_k-1
            # - c (z_k-1 - z_k-2) has variance (1 + (1 + c)^2 + c^2) r while the motion is
            # smooth (the initial value counts as one sample: a prior against a lucky first one)
            h = self._h
            if len(h) == 6:
                t1, h1x, h1y, t2, h2x, h2y = h
                if t1 > t2 and bt > t1:
                    c = (bt - t1) / (t1 - t2)
                    ex = bx - h1x - c * (h1x - h2x)
                    ey = by - h1y - c * (h1y - h2y)
                    e = 0.5 * (ex * ex + ey * ey) / (1.0 + (1.0 + c) * (1.0 + c) + c * c)
                    if e > 16.0 * r:
                        e = 16.0 * r
                    age += 1.0
                    if age < horizon:
                        e = r + (e - r) / (age + 1.0)
                        e = r_min if e < r_min else (r_max if e > r_max else e)
                        # the models' covariances are in units of r (while the data
                        # dominate them, as at the start, exactly): a revised r revises them
                        # too, or a track begun with r too small keeps a too small
                        # covariance, reads its own start as large innovations and raises q
                        # (round 2's slow q walk); past the horizon r moves by ~1 % a step
                        # and this is left out (it runs for every object in every frame)
                        f = e / r
                        r = e
                        sp *= f
                        mp *= f
                        mb *= f
                        mc *= f
                        ca *= f
                        cb *= f
                        cc *= f
                    else:
                        r += (e - r) / horizon
                        r = r_min if r < r_min else (r_max if r > r_max else r)
                self._h = (bt, bx, by, t1, h1x, h1y)
            else:
                self._h = (bt, bx, by, *h[:3])
        dt = t - t0 if t > t0 else 0.0
        # Markov switching over dt, then the mixing weights (still's share of each model's start)
        a = switch_sm * dt
        b = switch_ms * dt
        if a > 0.5:
            a = 0.5
        if b > 0.5:
            b = 0.5
        cs = (1.0 - a) * ms + b * (1.0 - ms)
        cm = 1.0 - cs
        dt2 = dt * dt
        if ms < 2e-6:
            # moving for sure (the probability at its floor): the moving model keeps its
            # state (still's share in its start is below 1e-8) and the still one restarts
            # where it is (still's own share, below 0.5 %, left out): the mixing costs nothing
            x0x, x0y, p0 = mx, my, mp + q_s * dt
            x1x, x1y, v1x, v1y, a1, b1, c1 = mx, my, mvx, mvy, mp, mb, mc
        else:
            ws_s = (1.0 - a) * ms / cs if cs > 1e-12 else 0.0
            wm_s = a * ms / cm if cm > 1e-12 else 0.0
            ws_m = 1.0 - ws_s
            wm_m = 1.0 - wm_s
            # each model's start is the mix of both (the spread of the means adds to the
            # covariance; the axes' spreads are averaged, the noise being isotropic); the
            # still model's velocity is 0, certain. In terms of the models' difference
            # d = s - m:
            dx = sx - mx
            dy = sy - my
            d2 = dx * dx + dy * dy
            # the still model's start, then its prediction (a random walk)
            x0x = mx + ws_s * dx
            x0y = my + ws_s * dy
            p0 = ws_s * sp + ws_m * mp + 0.5 * ws_s * ws_m * d2 + q_s * dt
            # the moving model's start, then constant velocity
            k = 0.5 * wm_s * wm_m
            x1x = mx + wm_s * dx
            x1y = my + wm_s * dy
            v1x = wm_m * mvx
            v1y = wm_m * mvy
            a1 = wm_s * sp + wm_m * mp + k * d2
            b1 = wm_m * mb - k * (dx * mvx + dy * mvy)
            c1 = wm_m * mc + k * (mvx * mvx + mvy * mvy)
        ap = a1 + 2.0 * dt * b1 + dt2 * c1 + q * dt2 * dt2 * 0.25
        bp = b1 + dt * c1 + q * dt2 * dt * 0.5
        cp = c1 + q * dt2
        # what the correction needs that does not depend on the measurement (once per
        # instant: a second camera's revise only redoes the rest): inverse innovation
        # variances, both gates, gains, corrected covariances, the prior odds, the next
        # outlier rate, the weight of a normalised innovation
        ss = p0 + r
        sm = ap + r
        iss = 1.0 / ss
        ism = 1.0 / sm
        g2 = gate2
        # gate: inside the gate of a model that is not all but ruled out (a model of
        # negligible probability can be wide enough to take anything)
        gs2 = g2 if cs >= 0.05 else -1.0
        gm2 = g2 if cm >= 0.05 else -1.0
        vchk = 0.0
        if rho > 1e-3 and gm2 > 0.0:
            # outliers seen: a measurement is the moving model's only where it is likelier
            # from it than a false detection ((1 - rho) N(d; S) > rho / area) and where it
            # leaves the velocity possible; right after a jump the prediction is wide, and
            # a wide gate would catch the next false detection and run off with it
            e = (1.0 - rho) / (rho * clutter * sm)
            if e < 1e8:
                e = 2.0 * _log(e) if e > 1.0 else 0.0
                if e < gm2:
                    gm2 = e
            vchk = 1.0
        k0 = ap * ism
        k1 = bp * ism
        g = p0 * iss
        # the cruise model: constant velocity with a small fixed q, beside the moving one
        # (not mixed with it: restarted from it, see revise); lam < 0: it rests (ruled
        # out by a maneuver: the moving model alone) until the time -lam
        if lam >= 0.0 or t >= -lam:
            if lam < 0.0:  # it wakes where the moving model is
                cx, cy, cvx, cvy, ca, cb, cc, lam = mx, my, mvx, mvy, mp, mb, mc, 1e-3
            qd = q_c * dt2
            cap = ca + 2.0 * dt * cb + dt2 * cc + qd * dt2 * 0.25
            cbp = cb + dt * cc + qd * dt * 0.5
            ccp = cc + qd
            isc = 1.0 / (cap + r)
            kc0 = cap * isc
            kc1 = cbp * isc
            e = switch_c * dt
            lp = lam + e * (1.0 - 2.0 * lam) if e < 0.5 else 0.5
            # its prediction, gains, corrected covariance, the prior odds moving / cruise x
            # the normalisations' ratio
            cpri: tuple[float, ...] | None = (
                cx + cvx * dt, cy + cvy * dt, cvx, cvy, cap, cbp, ccp, isc, kc0, kc1,
                (1.0 - kc0) * cap, (1.0 - kc0) * cbp, ccp - kc1 * cbp, lp,
                (1.0 - lp) * (cap + r) * ism / lp)
        else:
            cpri = None
        pri = (t, ta, dt, cs, cm, r, q, age, rho, ux, uy, x0x, x0y, p0,
               x1x + v1x * dt, x1y + v1y * dt, v1x, v1y, ap, bp, cp,
               iss, ism, gs2, gm2, vchk, g, (1.0 - g) * p0, k0, k1, (1.0 - k0) * ap,
               (1.0 - k0) * bp, cp - k1 * bp,
               # prior odds moving / still x the ratio of the Gaussians' normalisations (2-D)
               cm * ss / (cs * sm) if cs > 1e-300 else 1e300, rho * rho_keep,
               _sqrt(ism), cpri, lam)
        self._pri = pri if cache else None
        self._pri_h = self._h
        return self.revise(zx, zy, pri)

    def revise(self, zx: float, zy: float, pri: tuple[Any, ...] | None = None) -> Vec:
        """A second camera's measurement at the last step's instant instead of the last one:
        the measurement against the step's predictions again. ``pri``: update's own
        predictions (the step's second half: one function for both, since a call costs about
        a tenth of the correction, and this runs for every object each camera sees)."""
        if pri is None:
            pri = self._pri
            if pri is None or pri[0] != self.S[0]:  # no predictions of this step
                return self._redo(zx, zy)
            if not self._pure:
                self._restore()
            # (else the correction overwrites all the step changed after its predictions, and
            # restores the state before the step itself if it rejects the measurement: a
            # second camera's revise, the common case, costs the correction alone)
        (t, ta, dt, cs, cm, r, q, age, rho, ux, uy, x0x, x0y, p0, xpx, xpy, v1x, v1y, ap, bp,
         cp, iss, ism, gs2, gm2, vchk, g, sp, k0, k1, ap1, bp1, cp1, cr, rho1, w, cpri,
         lam) = pri
        nsx = zx - x0x
        nsy = zy - x0y
        nmx = zx - xpx
        nmy = zy - xpy
        d2s = (nsx * nsx + nsy * nsy) * iss
        d2m = (nmx * nmx + nmy * nmy) * ism
        vx = v1x + k1 * nmx
        vy = v1y + k1 * nmy
        if d2s > gs2 and (d2m > gm2 or (vchk and vx * vx + vy * vy > self.max_speed2)):
            if self._pure:  # a revise (see there)
                self._restore()
            if cpri is None:
                return self._rejected(t, dt, zx, zy, [
                    t, ta, cs, r, q, age, rho, x0x, x0y, p0, ap, xpx, xpy, v1x, v1y, bp, cp,
                    ux, uy, cs * x0x + cm * xpx, cs * x0y + cm * xpy,
                    xpx, xpy, v1x, v1y, ap, bp, cp, lam])
            cpx, cpy, cvx, cvy, cap, cbp, ccp, _, _, _, _, _, _, lp, _ = cpri
            mox = lp * cpx + (1.0 - lp) * xpx
            moy = lp * cpy + (1.0 - lp) * xpy
            return self._rejected(t, dt, zx, zy, [
                t, ta, cs, r, q, age, rho, x0x, x0y, p0, ap, xpx, xpy, v1x, v1y, bp, cp,
                ux, uy, cs * x0x + cm * mox, cs * x0y + cm * moy,
                cpx, cpy, cvx, cvy, cap, cbp, ccp, lp])
        # -- model probabilities: the Gaussian likelihood ratio still / moving
        e = 0.5 * (d2s - d2m)
        mu = 1.0 / (1.0 + cr * _exp(e if e < 700.0 else 700.0))
        mu = 1e-6 if mu < 1e-6 else (1.0 - 1e-6 if mu > 1.0 - 1e-6 else mu)
        # the noise estimates learn from this measurement at the next step (once per instant,
        # however often a second camera revises it)
        self._book = (t, zx, zy, d2m, nmx, nmy, w)
        if self._pend is not None or self._far is not None or self._backup is not None:
            self._pend = self._far = self._backup = None
        # -- corrections
        sx = x0x + g * nsx
        sy = x0y + g * nsy
        mx = xpx + k0 * nmx
        my = xpy + k0 * nmy
        # cruise / moving: the likelihood ratio; a cruise model all but ruled out (a maneuver)
        # rests, then restarts from the moving one (what an IMM's mixing would do, for less)
        if cpri is not None:
            cpx, cpy, cvx, cvy, _, _, _, isc, kc0, kc1, ca1, cb1, cc1, lp, crc = cpri
            ncx = zx - cpx
            ncy = zy - cpy
            e = 0.5 * ((ncx * ncx + ncy * ncy) * isc - d2m)
            lam = 1.0 / (1.0 + crc * _exp(e if e < 700.0 else 700.0))
            if lam > _C_FLOOR:
                if lam > 0.999:
                    lam = 0.999
                cx = cpx + kc0 * ncx
                cy = cpy + kc0 * ncy
                w = 1.0 - mu
                ex = mu * sx + w * (lam * cx + (1.0 - lam) * mx)
                ey = mu * sy + w * (lam * cy + (1.0 - lam) * my)
                self.S = [t, t, mu, r, q, age, rho1, sx, sy, sp, ap1, mx, my, vx, vy, bp1, cp1,
                          ux, uy, ex, ey, cx, cy, cvx + kc1 * ncx, cvy + kc1 * ncy, ca1, cb1,
                          cc1, lam]
                self._pure = True
                return (ex, ey)
            lam = -(t + self.c_rest)
        w = 1.0 - mu
        ex = mu * sx + w * mx
        ey = mu * sy + w * my
        self.S = [t, t, mu, r, q, age, rho1, sx, sy, sp, ap1, mx, my, vx, vy, bp1, cp1, ux, uy,
                  ex, ey, mx, my, vx, vy, ap1, bp1, cp1, lam]
        self._pure = True
        return (ex, ey)

    def _after_jump(self, t: float, zx: float, zy: float) -> bool:
        """The step after a jump re-initialised the track: keep the new track unless this
        measurement fits the old track (inside its gate) and is nearer its prediction than
        the new one's; then the jump was a stray measurement and the old track goes on.
        A measurement far from both (an outlier) decides nothing: True, it is not used and
        the next one decides, for up to 0.1 s after the jump. Why: three aligned outliers
        had taken a resting ball (20 mm noise, p = 0.2) and the outlier after them had
        confirmed the false track, 600 mm off for four frames (seed 3: 2.3 x the oracle)."""
        bk = self._backup
        self._backup = None
        assert bk is not None
        S = self.S  # (the new track as _init made it; its output may be the old track's)
        w = 1.0 - S[2]
        dt = t - S[0]
        nx, ny = zx - S[11] - w * S[13] * dt, zy - S[12] - w * S[14] * dt
        # the new track's gate (its prediction's variance: its velocity is uncertain), when
        # outliers have been seen; without them a far measurement is a maneuver, used at once
        gn = (self.gate2 * (S[10] + dt * (2.0 * S[15] + dt * S[16]) + S[_R])
              if S[_RHO] >= self.rho_accept else math.inf)
        cur = self._save()
        self._load(bk)
        S = self.S
        w = 1.0 - S[2]
        dt = t - S[0]
        ex, ey = self.estimate_fast()
        ox, oy = zx - ex - w * S[13] * dt, zy - ey - w * S[14] * dt
        o2 = ox * ox + oy * oy
        far = 2.0 * self.gate2 * S[_R]
        n2 = nx * nx + ny * ny
        if o2 > far or n2 <= o2:
            self._load(cur)  # far from the old track, or the new track is nearer
            if o2 > 4.0 * far and n2 > 4.0 * gn and t - S[0] < 0.1:
                self._backup = bk  # far from both: the next measurement decides
                return True
        self._backup = None
        return False

    def _rejected(self, t: float, dt: float, zx: float, zy: float, pred: list[float]) -> Vec:
        """A measurement outside both models' gates: an outlier, a maneuver or a new place.
        ``pred``: the state with both models' predictions and the prior probabilities."""
        self.rejected += 1
        S = self.S
        ex, ey = self.estimate_fast()
        dx, dy = zx - ex, zy - ey
        r = pred[_R]
        lim0 = math.sqrt(self.gate2 * r)
        reach = self.max_speed * (t - S[1]) + lim0
        pend = self._pend
        confirmed = False
        v = (0.0, 0.0)
        pvv = 0.0
        if pend is not None and t > pend[0]:  # does it continue the last reachable jump?
            px, py = zx - pend[1], zy - pend[2]
            tp = t - pend[0]
            lim = self.max_speed * tp + lim0
            # a maneuver continues away from where the object was, in about the same direction;
            # a track that drifted off sees two measurements that move as it does
            ox, oy = pend[1] - ex, pend[2] - ey
            along = px * ox + py * oy
            w = 1.0 - S[2]
            gx, gy = px - w * S[13] * tp, py - w * S[14] * tp
            if px * px + py * py <= min(lim * lim, self.max_speed ** 2 * tp * tp * 1.44) and (
                    (along > 0.0 and along * along >= 0.5 * (px * px + py * py)
                     * (ox * ox + oy * oy))
                    or gx * gx + gy * gy <= 2.0 * self.gate2 * r):
                confirmed = True
                v = (px / tp, py / tp)
                pvv = 4.0 * r / (tp * tp)  # a velocity from two measurements
        if confirmed or dx * dx + dy * dy <= reach * reach:
            if not confirmed and dt > 0.0 and pred[_RHO] < self.rho_accept:
                out = self._speed_up(t, dt, zx, zy, pred)
                if out is not None:
                    return out
            if not confirmed and dt > 0:
                v = (dx / dt, dy / dt)
            sp2 = v[0] * v[0] + v[1] * v[1]
            if sp2 > self.max_speed * self.max_speed:
                k = self.max_speed / math.sqrt(sp2)
                v = (v[0] * k, v[1] * k)
            if confirmed or pred[_RHO] < self.rho_accept:
                if not confirmed:  # from one measurement: the kick may have come mid-frame
                    pvv = v[0] * v[0] + v[1] * v[1] + r / max(dt, 1e-3) ** 2
                self.S = pred
                bk = self._save()
                self._init(t, zx, zy, v, mu=1e-3, pvv=pvv)
                self._backup = bk
                return (zx, zy)
            self._pend = (t, zx, zy)
        # three recent rejected measurements on one line at a possible speed: the track is
        # lost (started on an outlier, or a jump nobody confirmed) and that line is the object
        far = self._far or ()
        ms2 = self.max_speed * self.max_speed
        tol2 = 4.0 * self.gate2 * r
        for j in range(len(far) - 1, 0, -1):
            tj, xj, yj = far[j]
            d = t - tj
            if d <= 0.0:
                continue
            vx, vy = (zx - xj) / d, (zy - yj) / d
            if vx * vx + vy * vy > ms2:
                continue
            for i in range(j):
                ti, xi, yi = far[i]
                d = t - ti
                ox, oy = xi - zx + vx * d, yi - zy + vy * d
                if ox * ox + oy * oy <= tol2:
                    self.S = pred
                    bk = self._save()
                    self._init(t, zx, zy, (vx, vy))
                    self._backup = bk  # three aligned outliers: the next measurement tells
                    if len(pred) < 22:  # (1-D: the line is taken at once)
                        return (zx, zy)
                    d = S[1] - t  # the line and the old track at its last measurement used
                    ovx, ovy = _velocity(S)
                    if ((zx + vx * d - ex + ovx * (S[0] - S[1])) ** 2
                            + (zy + vy * d - ey + ovy * (S[0] - S[1])) ** 2 > tol2):
                        # a line that does not start where the object was (false detections
                        # in a line, or a lost track): until the next measurement tells, the
                        # output stays on the old track (a lost track waited three frames)
                        S = self.S
                        S[19], S[20] = pred[19], pred[20]  # (predict reads: held)
                        return (pred[19], pred[20])
                    return (zx, zy)
        self._far = (*(f for f in far[-5:] if t - f[0] < 0.3), (t, zx, zy))
        pred[_RHO] += (1.0 - pred[_RHO]) / self.horizon
        self.S = pred
        return self.estimate_fast()

    def _speed_up(self, t: float, dt: float, zx: float, zy: float,
                  pred: list[float]) -> Vec | None:
        """A measurement a little outside the gate with no outliers about: the motion changed
        more than q allows (a ball slowing down, a robot turning) and a jump would throw the
        velocity away. If raising q (at most to its bound) makes it a 3-sigma innovation, redo
        the step with that q (q then shrinks again as the data allow) and return the estimate;
        else None: a jump. Why: under constant deceleration q shrank to its floor, the lag grew
        past the gate and every such frame restarted the track from one measurement's velocity
        (the bounced ball at 2 mm noise, 1.2 x the oracle in round 2)."""
        nx, ny = zx - pred[11], zy - pred[12]
        ap, r, q = pred[10], pred[_R], pred[_Q]
        d4 = 0.25 * dt * dt * dt * dt
        qn = q + ((nx * nx + ny * ny) / 9.0 - r - ap) / d4
        q_max = self._k[4]
        if qn > q_max:
            qn = q_max
        if qn < 1.5 * q or (nx * nx + ny * ny) > self.gate2 * (ap + (qn - q) * d4 + r):
            return None
        # the state before the step with what it learnt from its book (noise estimates, bias
        # means, covariances rescaled with r), q raised; then the step again (it has nothing
        # left to learn: the book is spent)
        S = self.S.copy()
        f = r / S[_R]
        S[_R], S[_Q], S[5], S[17], S[18] = r, qn, pred[5], pred[17], pred[18]
        S[9] *= f
        S[10] *= f
        S[15] *= f
        S[16] *= f
        if len(S) > 21:
            S[25] *= f
            S[26] *= f
            S[27] *= f
        prev = self._prev
        held = _velocity(self.S) if pred[_MU] > 0.5 and self.dims == 2 else None
        self.S = S
        self.rejected -= 1  # (counted again if the redone step rejects it too)
        out = self.update(t, zx, zy)
        self._prev = prev
        self._pure = False  # (a revise restores the state before the outer step)
        # from rest, one measurement a little outside the gate moves the estimate a few mm but
        # must not report its velocity (0.5 m/s from a 4.5-sigma noise sample, about one frame
        # in 10^4 at 2 mm: the game controller reads a ball "not steady", docs/tracker.md);
        # the velocity before the step stands until the next measurement
        self._vheld = held
        return out

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


class AdaptiveIMM1D(AdaptiveIMM):
    """The same filter on x alone (orientation, through :class:`AngleFilter`; y is ignored
    and reads 0): the y arithmetic left out, since it runs for every robot in every frame."""

    __slots__ = ()

    dims = 1

    def __init__(self, params: AdaptiveParams | None = None, angle: bool = True) -> None:
        super().__init__(params, angle)

    def _init(self, t: float, x: float, y: float, v: Vec = (0.0, 0.0), mu: float = 0.5,
              pvv: float | None = None) -> Vec:
        # the still/moving pair alone (no cruise model): the state without its 2-D tail
        out = super()._init(t, x, y, v, mu, pvv)
        del self.S[21:]
        return out

    def velocity(self) -> Vec:
        bk = self._backup
        S: list[float] = self.S if bk is None else bk[0]  # type: ignore[assignment]
        if not S:
            return (0.0, 0.0)
        return ((1.0 - S[2]) * S[13], 0.0)

    def predict(self, t_s: float) -> Vec | None:
        S = self.S
        if not S:
            return None
        return (S[19] + (1.0 - S[2]) * (t_s - S[0]) * S[13], 0.0)

    def update(self, t: float, zx: float, zy: float) -> Vec:
        self._prev = (self.S, self._h, self._pend, self._far, self._backup, self._book)
        self._pure = False
        (gap_s, q_rate, q_down, q_min, q_max, horizon, r_min, r_max, switch_sm, switch_ms, q_s,
         gate2, _, rho_keep, _, _) = self._k
        cache = self._backup is None
        if not cache and self._after_jump(t, zx, 0.0):
            self.rejected += 1
            return self.predict(t) or (zx, 0.0)
        S = self.S
        if not S or t - S[0] > gap_s:
            return self._init(t, zx, 0.0)
        (t0, ta, ms, r, q, age, rho, sx, _, sp, mp, mx, _, mvx, _, mb, mc, ux, _, _, _) = S
        bk = self._book
        if bk is not None:  # as in the 2-D step
            self._book = None
            bt, bx, _, d2m, nm, _, w = bk
            ux += BIAS_A * (nm * w - ux)
            e = 0.5 * (d2m + ux * ux * 2.0 * BIAS_K)
            e = q_rate * ((e if e < 6.0 else 6.0) - q_down)
            q *= 1.0 + e + 0.5 * e * e
            q = q_min if q < q_min else (q_max if q > q_max else q)
            h = self._h
            if len(h) == 6:
                t1, h1x, _, t2, h2x, _ = h
                if t1 > t2 and bt > t1:
                    c = (bt - t1) / (t1 - t2)
                    ex = bx - h1x - c * (h1x - h2x)
                    e = ex * ex / (1.0 + (1.0 + c) * (1.0 + c) + c * c)
                    if e > 16.0 * r:
                        e = 16.0 * r
                    age += 1.0
                    if age < horizon:
                        e = r + (e - r) / (age + 1.0)
                        e = r_min if e < r_min else (r_max if e > r_max else e)
                        # the models' covariances are in units of r (while the data
                        # dominate them, as at the start, exactly): a revised r revises them
                        # too, or a track begun with r too small keeps a too small
                        # covariance, reads its own start as large innovations and raises q
                        # (round 2's slow q walk); past the horizon r moves by ~1 % a step
                        # and this is left out (it runs for every object in every frame)
                        f = e / r
                        r = e
                        sp *= f
                        mp *= f
                        mb *= f
                        mc *= f
                    else:
                        r += (e - r) / horizon
                        r = r_min if r < r_min else (r_max if r > r_max else r)
                self._h = (bt, bx, 0.0, t1, h1x, 0.0)
            else:
                self._h = (bt, bx, 0.0, *h[:3])
        dt = t - t0 if t > t0 else 0.0
        a = switch_sm * dt
        b = switch_ms * dt
        if a > 0.5:
            a = 0.5
        if b > 0.5:
            b = 0.5
        cs = (1.0 - a) * ms + b * (1.0 - ms)
        cm = 1.0 - cs
        dt2 = dt * dt
        if ms < 2e-6:  # moving for sure (as in 2-D)
            x0, p0, x1, v1, a1, b1, c1 = mx, mp + q_s * dt, mx, mvx, mp, mb, mc
        else:
            ws_s = (1.0 - a) * ms / cs if cs > 1e-12 else 0.0
            wm_s = a * ms / cm if cm > 1e-12 else 0.0
            ws_m = 1.0 - ws_s
            wm_m = 1.0 - wm_s
            d = sx - mx
            x0 = mx + ws_s * d
            p0 = ws_s * sp + ws_m * mp + ws_s * ws_m * d * d + q_s * dt
            k = wm_s * wm_m
            x1 = mx + wm_s * d
            v1 = wm_m * mvx
            a1 = wm_s * sp + wm_m * mp + k * d * d
            b1 = wm_m * mb - k * d * mvx
            c1 = wm_m * mc + k * mvx * mvx
        ap = a1 + 2.0 * dt * b1 + dt2 * c1 + q * dt2 * dt2 * 0.25
        bp = b1 + dt * c1 + q * dt2 * dt * 0.5
        cp = c1 + q * dt2
        # what the correction needs that does not depend on the measurement (as in 2-D)
        ss = p0 + r
        sm = ap + r
        iss = 1.0 / ss
        ism = 1.0 / sm
        g2 = gate2
        k0 = ap * ism
        k1 = bp * ism
        g = p0 * iss
        pri = (t, ta, dt, cs, cm, r, q, age, rho, ux, x0, p0, x1 + v1 * dt, v1, ap, bp, cp,
               iss, ism, g2 if cs >= 0.05 else -1.0, g2 if cm >= 0.05 else -1.0, g,
               (1.0 - g) * p0, k0, k1, (1.0 - k0) * ap, (1.0 - k0) * bp, cp - k1 * bp,
               cm * _sqrt(ss * ism) / cs if cs > 1e-300 else 1e300, rho * rho_keep,
               _sqrt(ism))
        self._pri = pri if cache else None
        self._pri_h = self._h
        return self.revise(zx, 0.0, pri)

    def revise(self, zx: float, zy: float, pri: tuple[Any, ...] | None = None) -> Vec:
        if pri is None:  # as in 2-D
            pri = self._pri
            if pri is None or pri[0] != self.S[0]:
                return self._redo(zx, zy)
            if not self._pure:
                self._restore()
        (t, ta, dt, cs, cm, r, q, age, rho, ux, x0, p0, xp, v1, ap, bp, cp, iss, ism, gs2, gm2,
         g, sp, k0, k1, ap1, bp1, cp1, cr, rho1, w) = pri
        ns = zx - x0
        nm = zx - xp
        d2s = ns * ns * iss
        d2m = nm * nm * ism
        if d2s > gs2 and d2m > gm2:
            if self._pure:
                self._restore()
            return self._rejected(t, dt, zx, 0.0, [
                t, ta, cs, r, q, age, rho, x0, 0.0, p0, ap, xp, 0.0, v1, 0.0, bp, cp, ux, 0.0,
                cs * x0 + cm * xp, 0.0])
        e = 0.5 * (d2s - d2m)
        mu = 1.0 / (1.0 + cr * _exp(e if e < 700.0 else 700.0))
        mu = 1e-6 if mu < 1e-6 else (1.0 - 1e-6 if mu > 1.0 - 1e-6 else mu)
        self._book = (t, zx, 0.0, d2m, nm, 0.0, w)
        if self._pend is not None or self._far is not None or self._backup is not None:
            self._pend = self._far = self._backup = None
        sx = x0 + g * ns
        mx = xp + k0 * nm
        ex = mu * sx + (1.0 - mu) * mx
        self.S = [t, t, mu, r, q, age, rho1, sx, 0.0, sp, ap1, mx, 0.0, v1 + k1 * nm, 0.0, bp1,
                  cp1, ux, 0.0, ex, 0.0]
        self._pure = True
        return (ex, 0.0)
