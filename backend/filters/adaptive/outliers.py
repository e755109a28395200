"""The adaptive filter's outlier logic: what becomes of a measurement outside both models'
gates. Outliers and maneuvers (a kick, a bounce) both show up as a measurement far outside the
gate. They are told apart by physics and by the data: a measurement farther than the object
could have travelled (``max_speed``) is an outlier; a reachable one is a maneuver at once when
no outliers have been seen lately, otherwise when the next measurement confirms it (one frame
of delay, only in outlier-ridden data). A measurement only a little outside the gate, with no
outliers about, is neither: the motion changed more than q allows (a ball slowing down), and q
is raised and the step redone rather than the track restarted (``_speed_up``). A run of
consistent far measurements (the ball placed elsewhere) re-initialises the filter; the step
after a jump may still go back to the old track (``_after_jump``).

The outlier rate these decisions read is estimated from the gate's verdicts: it rises here,
with each rejected measurement, and decays in the step, with each accepted one.
"""

from __future__ import annotations

import math

from .state import _MU, _Q, _R, _RHO, AdaptiveState, Vec, _velocity


class Outliers(AdaptiveState):
    """The rejections, jumps and re-acquisitions of ``AdaptiveIMM`` (methods the step calls:
    a measurement outside the gates costs these calls, one inside none)."""

    __slots__ = ()

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
