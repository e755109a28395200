"""Does the adaptive filter's step pay as numpy arrays of robots? (issue 29, "robots as arrays";
a prototype and its figures, not a test.)

``batch_update`` is ``AdaptiveIMM.update`` (the 2-D filter of a robot's position: the step,
then the correction with the measurement) for N filters at once, in numpy, on the path a
tracked robot takes in nearly every step: a track with a state, no jump pending, the last
measurement's book to learn from and two measurements before it. Its branches (the noise
learning's start, the moving-for-sure shortcut, the outlier gate's clutter bound, the cruise
model resting, waking or ruled out) are computed for every row and picked with masks. Rows off
that path (a new track, a gap, a jump pending, a measurement outside the gates) are stepped by
the scalar filter, from the state they had: the batch changes nothing of them. ``exp`` and
``log`` go through ``math`` per row (numpy's own may differ from the C library's in the last
bit; ``--np-exp`` uses numpy's and reports the difference).

Input: fieldsim's cameras triggered together (11 v 11, division A, 8 x 75 Hz, every robot
driving; bench/world_split.py's frames) through the world model, each robot position filter's
calls recorded; then replayed twice on fresh filters, per instant its steps (one per robot,
independent of each other) first and its second cameras' revisions after:
scalar, one call a step; batched, the steps in chunks of N. Every state after every call is
compared bit for bit (the state list, the book, the history, the predictions a revise reads).
Timed: the steps alone (CPU time via the wall clock of the steps, best of ``--reps``).

    PYTHONPATH=. .venv/bin/python bench/batch_filter_bench.py [--n 1 4 8 22] [--reps 5]
        [--seconds 4] [--np-exp]
"""

from __future__ import annotations

import argparse
import math
import struct
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from backend.filters.adaptive import AdaptiveIMM
from backend.filters.adaptive.step import _C_FLOOR, BIAS_A, BIAS_K
from bench.world_split import Recorder, fieldsim_frames, passes, run_model

_exp, _log = math.exp, math.log


def _math_exp(a: np.ndarray) -> np.ndarray:
    return np.array([_exp(v) for v in a.tolist()])


def batch_update(fs: list[AdaptiveIMM], t: float, zx: np.ndarray, zy: np.ndarray,
                 exp: Callable[[np.ndarray], np.ndarray] = _math_exp) -> int:
    """``f.update(t, zx[i], zy[i])`` for each filter ``f = fs[i]`` (all of one parameter set,
    one instant). Returns how many rows went the batched way."""
    k0_ = fs[0]._k
    gap_s = k0_[0]
    ok = [f._backup is None and f.S and t - f.S[0] <= gap_s and f._book is not None
          and len(f._h) == 6 for f in fs]
    rows = [i for i, o in enumerate(ok) if o]
    batched = 0
    if rows:
        batched = _batch(fs, rows, t, zx, zy, k0_, exp)
    for i, o in enumerate(ok):
        if not o:
            fs[i].update(t, float(zx[i]), float(zy[i]))
    return batched


def _batch(fs: list[AdaptiveIMM], rows: list[int], t: float, zx_all: np.ndarray,
           zy_all: np.ndarray, k: tuple[float, ...],
           exp: Callable[[np.ndarray], np.ndarray]) -> int:
    (_, q_rate, q_down, q_min, q_max, horizon, r_min, r_max, switch_sm, switch_ms, q_s,
     gate2, clutter, rho_keep, q_c, switch_c) = k
    sel = [fs[i] for i in rows]
    zx, zy = zx_all[rows], zy_all[rows]
    S = np.array([f.S for f in sel]).T
    B = np.array([f._book for f in sel]).T
    H = np.array([f._h for f in sel]).T
    (t0, ta, ms, r, q, age, rho, sx, sy, sp, mp, mx, my, mvx, mvy, mb, mc, ux, uy, _, _,
     cx, cy, cvx, cvy, ca, cb, cc, lam) = S
    bt, bx, by, d2m, nmx, nmy, w = B
    t1, h1x, h1y, t2, h2x, h2y = H
    where = np.where
    # -- the noise estimates (learnt from the book)
    ux = ux + BIAS_A * (nmx * w - ux)
    uy = uy + BIAS_A * (nmy * w - uy)
    e = 0.5 * (0.5 * d2m + (ux * ux + uy * uy) * BIAS_K)
    e = q_rate * (np.minimum(e, 6.0) - q_down)  # (e if e < 6 else 6: the same for non-NaN)
    q = q * (1.0 + e + 0.5 * e * e)
    q = where(q < q_min, q_min, where(q > q_max, q_max, q))
    lrn = (t1 > t2) & (bt > t1)
    c = (bt - t1) / where(lrn, t1 - t2, 1.0)
    ex = bx - h1x - c * (h1x - h2x)
    ey = by - h1y - c * (h1y - h2y)
    e = 0.5 * (ex * ex + ey * ey) / (1.0 + (1.0 + c) * (1.0 + c) + c * c)
    e = where(e > 16.0 * r, 16.0 * r, e)
    age1 = age + 1.0
    young = lrn & (age1 < horizon)
    old = lrn & ~young
    ey_ = r + (e - r) / (age1 + 1.0)
    ey_ = where(ey_ < r_min, r_min, where(ey_ > r_max, r_max, ey_))
    f = where(young, ey_ / r, 1.0)
    eo = r + (e - r) / horizon
    eo = where(eo < r_min, r_min, where(eo > r_max, r_max, eo))
    r = where(young, ey_, where(old, eo, r))
    age = where(lrn, age1, age)
    # (x * 1.0 is x: the rows not rescaled keep their bits)
    sp, mp, mb, mc, ca, cb, cc = sp * f, mp * f, mb * f, mc * f, ca * f, cb * f, cc * f
    # -- the models: switching, mixing, prediction
    dt = where(t > t0, t - t0, 0.0)
    a = np.minimum(switch_sm * dt, 0.5)
    b = np.minimum(switch_ms * dt, 0.5)
    cs = (1.0 - a) * ms + b * (1.0 - ms)
    cm = 1.0 - cs
    dt2 = dt * dt
    sure = ms < 2e-6
    ws_s = where(cs > 1e-12, (1.0 - a) * ms / where(cs > 1e-12, cs, 1.0), 0.0)
    wm_s = where(cm > 1e-12, a * ms / where(cm > 1e-12, cm, 1.0), 0.0)
    ws_m = 1.0 - ws_s
    wm_m = 1.0 - wm_s
    dx = sx - mx
    dy = sy - my
    d2 = dx * dx + dy * dy
    kk = 0.5 * wm_s * wm_m
    x0x = where(sure, mx, mx + ws_s * dx)
    x0y = where(sure, my, my + ws_s * dy)
    p0 = where(sure, mp + q_s * dt, ws_s * sp + ws_m * mp + 0.5 * ws_s * ws_m * d2 + q_s * dt)
    x1x = where(sure, mx, mx + wm_s * dx)
    x1y = where(sure, my, my + wm_s * dy)
    v1x = where(sure, mvx, wm_m * mvx)
    v1y = where(sure, mvy, wm_m * mvy)
    a1 = where(sure, mp, wm_s * sp + wm_m * mp + kk * d2)
    b1 = where(sure, mb, wm_m * mb - kk * (dx * mvx + dy * mvy))
    c1 = where(sure, mc, wm_m * mc + kk * (mvx * mvx + mvy * mvy))
    ap = a1 + 2.0 * dt * b1 + dt2 * c1 + q * dt2 * dt2 * 0.25
    bp = b1 + dt * c1 + q * dt2 * dt * 0.5
    cp = c1 + q * dt2
    ss = p0 + r
    sm = ap + r
    iss = 1.0 / ss
    ism = 1.0 / sm
    gs2 = where(cs >= 0.05, gate2, -1.0)
    gm2 = where(cm >= 0.05, gate2, -1.0)
    k0 = ap * ism
    k1 = bp * ism
    g = p0 * iss
    vchk = (rho > 1e-3) & (gm2 > 0.0)
    if vchk.any():  # outliers seen: the clutter bound on the moving model's gate (rare)
        for j in np.flatnonzero(vchk).tolist():
            e1 = (1.0 - rho[j]) / (rho[j] * clutter * sm[j])
            if e1 < 1e8:
                e1 = 2.0 * _log(e1) if e1 > 1.0 else 0.0
                if e1 < gm2[j]:
                    gm2[j] = e1
    vchkf = vchk.astype(float)
    # the cruise model: awake, waking, or resting
    on = (lam >= 0.0) | (t >= -lam)
    wake = on & (lam < 0.0)
    cx = where(wake, mx, cx)
    cy = where(wake, my, cy)
    cvx = where(wake, mvx, cvx)
    cvy = where(wake, mvy, cvy)
    ca = where(wake, mp, ca)
    cb = where(wake, mb, cb)
    cc = where(wake, mc, cc)
    lam = where(wake, 1e-3, lam)
    qd = q_c * dt2
    cap = ca + 2.0 * dt * cb + dt2 * cc + qd * dt2 * 0.25
    cbp = cb + dt * cc + qd * dt * 0.5
    ccp = cc + qd
    isc = 1.0 / (cap + r)
    kc0 = cap * isc
    kc1 = cbp * isc
    e = switch_c * dt
    lp = where(e < 0.5, lam + e * (1.0 - 2.0 * lam), 0.5)
    cpx = cx + cvx * dt
    cpy = cy + cvy * dt
    ca1 = (1.0 - kc0) * cap
    cb1 = (1.0 - kc0) * cbp
    cc1 = ccp - kc1 * cbp
    crc = (1.0 - lp) * (cap + r) * ism / lp
    xpx = x1x + v1x * dt
    xpy = x1y + v1y * dt
    sp1 = (1.0 - g) * p0
    ap1 = (1.0 - k0) * ap
    bp1 = (1.0 - k0) * bp
    cp1 = cp - k1 * bp
    cr = where(cs > 1e-300, cm * ss / where(cs > 1e-300, cs * sm, 1.0), 1e300)
    rho1 = rho * rho_keep
    wsq = np.sqrt(ism)
    # -- the correction
    nsx = zx - x0x
    nsy = zy - x0y
    nmx = zx - xpx
    nmy = zy - xpy
    d2s = (nsx * nsx + nsy * nsy) * iss
    d2m = (nmx * nmx + nmy * nmy) * ism
    vx = v1x + k1 * nmx
    vy = v1y + k1 * nmy
    max_speed2 = sel[0].max_speed2
    rej = (d2s > gs2) & ((d2m > gm2) | (vchk & (vx * vx + vy * vy > max_speed2)))
    e = 0.5 * (d2s - d2m)
    mu = 1.0 / (1.0 + cr * exp(np.minimum(e, 700.0)))
    mu = where(mu < 1e-6, 1e-6, where(mu > 1.0 - 1e-6, 1.0 - 1e-6, mu))
    sx = x0x + g * nsx
    mx = xpx + k0 * nmx
    sy = x0y + g * nsy
    my = xpy + k0 * nmy
    ncx = zx - cpx
    ncy = zy - cpy
    e = 0.5 * ((ncx * ncx + ncy * ncy) * isc - d2m)
    lc = 1.0 / (1.0 + crc * exp(np.minimum(e, 700.0)))
    keep = on & (lc > _C_FLOOR)
    lc = np.minimum(lc, 0.999)
    ccx = cpx + kc0 * ncx
    ccy = cpy + kc0 * ncy
    w1 = 1.0 - mu
    exk = mu * sx + w1 * (lc * ccx + (1.0 - lc) * mx)
    eyk = mu * sy + w1 * (lc * ccy + (1.0 - lc) * my)
    exm = mu * sx + w1 * mx
    eym = mu * sy + w1 * my
    lam_out = where(keep, lc, where(on, -(t + sel[0].c_rest), lam))
    out = np.array([
        np.full_like(mu, t), np.full_like(mu, t), mu, r, q, age, rho1, sx, sy, sp1, ap1, mx, my,
        vx, vy, bp1, cp1, ux, uy, where(keep, exk, exm), where(keep, eyk, eym),
        where(keep, ccx, mx), where(keep, ccy, my), where(keep, cvx + kc1 * ncx, vx),
        where(keep, cvy + kc1 * ncy, vy), where(keep, ca1, ap1), where(keep, cb1, bp1),
        where(keep, cc1, cp1), lam_out]).T.tolist()
    # what a second camera's revise reads, per row: the step's predictions
    pri_cols = np.array([
        np.full_like(mu, t), ta, dt, cs, cm, r, q, age, rho, ux, uy, x0x, x0y, p0, xpx, xpy,
        v1x, v1y, ap, bp, cp, iss, ism, gs2, gm2, vchkf, g, sp1, k0, k1, ap1, bp1, cp1, cr,
        rho1, wsq, lam]).T.tolist()
    cpri_cols = np.array([cpx, cpy, cvx, cvy, cap, cbp, ccp, isc, kc0, kc1, ca1, cb1, cc1, lp,
                          crc]).T.tolist()
    book = np.array([np.full_like(mu, t), zx, zy, d2m, nmx, nmy, wsq]).T.tolist()
    rej_l = rej.tolist()
    on_l = on.tolist()
    n = 0
    for j, fl in enumerate(sel):
        if rej_l[j]:  # outside the gates: the scalar step, from the state it had
            fl.update(t, float(zx[j]), float(zy[j]))
            continue
        n += 1
        h = fl._h
        fl._prev = (fl.S, h, fl._pend, fl._far, None, fl._book)
        fl._vheld = None
        bk = fl._book
        assert bk is not None
        nh = (bk[0], bk[1], bk[2], h[0], h[1], h[2])
        fl._h = nh
        pc = pri_cols[j]
        lam_j = pc.pop()
        fl._pri = (*pc, tuple(cpri_cols[j]) if on_l[j] else None, lam_j)
        fl._pri_h = nh
        fl._book = tuple(book[j])
        fl._pend = fl._far = None
        fl.S = out[j]
        fl._pure = True
    return n


def ulps(a: float, b: float) -> int:
    if a == b:
        return 0
    ia: int = struct.unpack("<q", struct.pack("<d", a))[0]
    ib: int = struct.unpack("<q", struct.pack("<d", b))[0]
    return abs(ia - ib)


def state_of(f: AdaptiveIMM) -> list[Any]:
    return [f.S, f._book, f._h, f._pri, f._pri_h, f._pend, f._far, f._backup, f._vheld,
            f._pure, f._prev]


def max_ulp(x: Any, y: Any) -> int:
    if isinstance(x, float) and isinstance(y, float):
        return ulps(x, y)
    if isinstance(x, (list, tuple)) and isinstance(y, (list, tuple)) and len(x) == len(y):
        return max((max_ulp(a, b) for a, b in zip(x, y, strict=True)), default=0)
    return 0 if x == y else 1 << 62


def instants(calls: list[tuple[Any, str, tuple[float, ...]]]) -> list[
        tuple[list[tuple[int, tuple[float, ...]]], list[tuple[int, str, tuple[float, ...]]]]]:
    """The recorded calls per instant: each filter's first call in it (its step: filter
    index, (t, x, y)), and the rest in order (the second cameras' revisions). Steps of
    different filters are independent: run first, each filter's own calls keep their order."""
    index: dict[int, int] = {}
    out: list[tuple[list[tuple[int, tuple[float, ...]]],
                    list[tuple[int, str, tuple[float, ...]]]]] = []
    cur_t: float | None = None
    stepped: set[int] = set()
    for flt, name, args in calls:
        i = index.setdefault(id(flt), len(index))
        if name == "update" and args[0] != cur_t:
            cur_t = args[0]
            out.append(([], []))
            stepped = set()
        steps, rest = out[-1]
        if name == "update" and i not in stepped:
            stepped.add(i)
            steps.append((i, args))
        else:
            rest.append((i, name, args))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, nargs="+", default=[1, 4, 8, 22])
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--np-exp", action="store_true", help="numpy's exp instead of math's")
    a = ap.parse_args()
    exp = np.exp if a.np_exp else _math_exp
    frames, poses = fieldsim_frames("together", a.seconds)
    with Recorder() as rec:
        m, _, _, _ = run_model(passes(frames, 8), poses)
    xy = {id(tr.pos) for tr in m._robots.values()}
    calls = [c for c in rec.calls if id(c[0]) in xy]
    nfil = len(xy)
    inst = instants(calls)
    nsteps = sum(len(s) for s, _ in inst)
    print(f"fieldsim together, {len(frames)} frames: {len(calls)} robot position filter calls, "
          f"{nsteps} steps in {len(inst)} instants ({nsteps / len(inst):.1f} a step batch at "
          f"most), exp: {'numpy' if a.np_exp else 'math, per row'}; load "
          f"{Path('/proc/loadavg').read_text().split()[0]}")

    def replay(n: int | None) -> float:
        fs = [AdaptiveIMM() for _ in range(nfil)]
        clock = time.perf_counter
        spent = 0.0
        for steps, rest in inst:
            if n is None:
                c0 = clock()
                for i, (t, x, y) in steps:
                    fs[i].update(t, x, y)
                spent += clock() - c0
            else:
                for s in range(0, len(steps), n):
                    chunk = steps[s:s + n]
                    c0 = clock()  # (the arrays' making counted: a caller would make them)
                    batch_update([fs[i] for i, _ in chunk], chunk[0][1][0],
                                 np.array([c[1][1] for c in chunk]),
                                 np.array([c[1][2] for c in chunk]), exp)
                    spent += clock() - c0
            for i, name, args in rest:
                getattr(fs[i], name)(*args)
        return spent

    best_s = min(replay(None) for _ in range(a.reps))
    print(f"  scalar: {best_s / nsteps * 1e6:.2f} us a step")
    for n in a.n:
        # correctness: against the scalar replay, state by state, instant by instant
        ref = [AdaptiveIMM() for _ in range(nfil)]
        got = [AdaptiveIMM() for _ in range(nfil)]
        worst = 0
        batched = 0
        for steps, rest in inst:
            for i, (t, x, y) in steps:
                ref[i].update(t, x, y)
            for s in range(0, len(steps), n):
                chunk = steps[s:s + n]
                batched += batch_update([got[i] for i, _ in chunk], chunk[0][1][0],
                                        np.array([c[1][1] for c in chunk]),
                                        np.array([c[1][2] for c in chunk]), exp)
            for i, _ in steps:
                worst = max(worst, max_ulp(state_of(got[i]), state_of(ref[i])))
            for i, name, args in rest:
                getattr(ref[i], name)(*args)
                getattr(got[i], name)(*args)
                worst = max(worst, max_ulp(state_of(got[i]), state_of(ref[i])))
        best = min(replay(n) for _ in range(a.reps))
        print(f"  batched N={n:2d}: {best / nsteps * 1e6:6.2f} us a step "
              f"({best / best_s:.2f} x scalar), {batched / nsteps * 100:.1f} % of steps "
              f"batched, max difference from scalar {worst} ulp")


if __name__ == "__main__":
    main()
