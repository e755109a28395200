"""Vision filter experiment: the paper's Fig. 2, synthetic error tables, the acceptance table of
the adaptive default filter (``acceptance.py``), and end to end.

    .venv/bin/python -m experiments.filters.run --out docs/experiments/filters

Fixed seeds. Writes fig2.svg, lag.svg, results.json and README.md into --out. ``--no-e2e``
skips the end-to-end part (starting the real station with fieldsim).
"""

from __future__ import annotations

import argparse
import bisect
import json
import math
import os
import random
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Callable
from pathlib import Path
from typing import Any

from backend.filters import (
    FILTER_KINDS,
    AdaptiveIMM,
    FilterSettings,
    KalmanCV,
    KalmanParams,
    MedianFilter,
    PaperFilter,
    PaperParams,
    PositionFilter,
    RawFilter,
)

from . import acceptance
from .svgplot import Series, line_plot

ROOT = Path(__file__).resolve().parents[2]
DT = 1 / 60  # one camera at 60 Hz
NOISE_MM = 3.0

FilterMaker = Callable[[], PositionFilter]
FILTERS: list[tuple[str, FilterMaker]] = [
    ("raw", RawFilter),
    ("median (N=5)", MedianFilter),
    ("paper: median + weighted avg (0.05/0.95)", PaperFilter),
    ("Kalman CV (defaults, no gate)", KalmanCV.from_params),
    ("Kalman CV, gate 150 mm", lambda: KalmanCV.from_params(KalmanParams(gate_mm=150.0))),
    ("adaptive", AdaptiveIMM),
]


# -- (a) Fig. 2 ------------------------------------------------------------------------------

def fig2(out: Path, seed: int) -> dict[str, float]:
    rng = random.Random(seed)
    n = 300
    ts = [i * DT for i in range(n)]

    def truth(t: float) -> float:  # still, then 0.3 m/s for 2 s, then still
        return 500.0 + 300.0 * min(max(t - 1.5, 0.0), 2.0)

    true = [truth(t) for t in ts]
    meas = []
    for v in true:
        z = v + rng.gauss(0.0, 5.0)
        if rng.random() < 0.2:
            z += rng.choice((-1, 1)) * rng.uniform(100.0, 400.0)
        meas.append(z)
    med, fin = MedianFilter(), PaperFilter()
    med_out = [med.update(t, z, 0.0)[0] for t, z in zip(ts, meas, strict=True)]
    fin_out = [fin.update(t, z, 0.0)[0] for t, z in zip(ts, meas, strict=True)]
    svg = line_plot([
        Series("true value", ts, true, "#2a9d3a", width=2.5),
        Series("measurements (outliers p=0.2)", ts, meas, "#d62728", style="dots"),
        Series("median filter (N=5)", ts, med_out, "#9b59b6", width=1.5),
        Series("final: 0.95 prev + 0.05 median", ts, fin_out, "#8b0000", width=2.5),
    ], "Generated data filtering (as the paper's Fig. 2): noise 5 mm, outliers p=0.2",
        "time (s), 60 Hz", "position x (mm)", ylim=(0.0, 1500.0))
    (out / "fig2.svg").write_text(svg)

    def err(xs: list[float]) -> tuple[float, float]:
        e = [x - v for x, v, t in zip(xs, true, ts, strict=True) if t >= 0.5]
        return math.sqrt(sum(v * v for v in e) / len(e)), max(abs(v) for v in e)

    r = {}
    for name, xs in (("raw", meas), ("median", med_out), ("paper", fin_out)):
        rm, mx = err(xs)
        r[f"{name}_rmse"], r[f"{name}_max"] = rm, mx
    still = [(x - v) for x, v, t in zip(fin_out, true, ts, strict=True) if 0.5 <= t < 1.5]
    r["paper_still_std"] = math.sqrt(sum(e * e for e in still) / len(still))
    return r


# -- (b) synthetic cases ---------------------------------------------------------------------

Traj = Callable[[float], tuple[float, float]]


def stationary(t: float) -> tuple[float, float]:
    return (1000.0, 500.0)


def constant_speed(v_mm_s: float) -> Traj:
    return lambda t: (-1500.0 + v_mm_s * t, 200.0)


def bounce(t: float) -> tuple[float, float]:
    """Ball at 3 m/s along +x hits a robot at t=1 s and comes back at 0.9 m/s (restitution
    0.3), both phases decelerating at 0.4 m/s^2 (fieldsim's rolling friction)."""
    tb = 1.0
    if t <= tb:
        return (-3000.0 + 3000.0 * t - 200.0 * t * t, 300.0)
    xb = -3000.0 + 3000.0 * tb - 200.0 * tb * tb
    s = t - tb
    return (xb - 900.0 * s + 200.0 * s * s, 300.0 + 150.0 * s)


def run_case(traj: Traj, maker: FilterMaker, seconds: float, p_out: float, rng: random.Random,
             warmup_s: float = 0.5) -> tuple[list[float], list[float]]:
    f = maker()
    errs, along = [], []
    n = int(seconds / DT)
    for i in range(n):
        t = i * DT
        x, y = traj(t)
        zx, zy = x + rng.gauss(0, NOISE_MM), y + rng.gauss(0, NOISE_MM)
        if rng.random() < p_out:  # a false detection, e.g. the ball "on a robot" nearby
            a = rng.uniform(0, 2 * math.pi)
            d = rng.uniform(200.0, 1000.0)
            zx, zy = zx + d * math.cos(a), zy + d * math.sin(a)
        ex, ey = f.update(t, zx, zy)
        if t >= warmup_s:
            errs.append(math.hypot(ex - x, ey - y))
            along.append(x - ex)
    return errs, along


def tables(seed: int, runs: int) -> dict[str, Any]:
    cases: list[tuple[str, Traj, float]] = [
        ("stationary", stationary, 4.0),
        ("constant 1 m/s", constant_speed(1000.0), 3.0),
        ("constant 0.5 m/s", constant_speed(500.0), 3.0),
        ("ball bouncing off a robot (3 m/s -> 0.9 m/s back at t=1 s)", bounce, 2.0),
    ]
    res: dict[str, Any] = {}
    for p_out in (0.2, 0.0):
        block: dict[str, Any] = {}
        for cname, traj, secs in cases:
            row: dict[str, Any] = {}
            for fname, maker in FILTERS:
                rng = random.Random(seed)
                allerr: list[float] = []
                for _ in range(runs):
                    e, _ = run_case(traj, maker, secs, p_out, rng)
                    allerr += e
                allerr.sort()
                row[fname] = {
                    "rmse": math.sqrt(sum(v * v for v in allerr) / len(allerr)),
                    "p95": allerr[int(0.95 * (len(allerr) - 1))],
                    "max": allerr[-1],
                }
            block[cname] = row
        res[f"p_out={p_out}"] = block
    # lag of the paper filter on a constant speed (no outliers): measured vs predicted
    lag = []
    for v in (250.0, 500.0, 1000.0, 2000.0):
        for label, params in (("paper defaults (jump 200 mm)", PaperParams()),
                              ("paper, jump 10 m (no re-init)", PaperParams(jump_mm=10000.0))):
            rng = random.Random(seed)
            _, along = run_case(constant_speed(v), lambda p=params: PaperFilter(p), 6.0, 0.0,
                                rng, warmup_s=3.0)
            predicted = v * DT * 0.95 / 0.05 + 2 * v * DT  # + the median's 2-sample delay
            lag.append({"v_mm_s": v, "filter": label, "predicted_mm": predicted,
                        "mean_mm": sum(along) / len(along), "max_mm": max(along)})
    res["lag"] = lag
    return res


def lag_figure(out: Path, seed: int) -> None:
    rng = random.Random(seed)
    ts, truth, series = [], [], {}
    makers: list[tuple[str, FilterMaker, str]] = [
        ("paper (jump 200 mm)", PaperFilter, "#8b0000"),
        ("paper, no re-init", lambda: PaperFilter(PaperParams(jump_mm=10000.0)), "#e07b39"),
        ("median", MedianFilter, "#9b59b6"),
        ("Kalman CV", KalmanCV.from_params, "#1f77b4"),
        ("adaptive (default)", AdaptiveIMM, "#2a9d3a"),
    ]
    fs = {name: m() for name, m, _ in makers}
    for name in fs:
        series[name] = []
    for i in range(int(3.0 / DT)):
        t = i * DT
        x = 1000.0 * t
        z = x + rng.gauss(0, NOISE_MM)
        ts.append(t)
        truth.append(x)
        for name, f in fs.items():
            series[name].append(x - f.update(t, z, 0.0)[0])
    sv = [Series(name, ts, series[name], color) for name, _, color in makers]
    (out / "lag.svg").write_text(line_plot(
        sv, "Object at constant 1 m/s, noise 3 mm, 60 Hz: lag of each filter",
        "time (s)", "lag = true x - estimate (mm)"))


# -- (c) end to end -------------------------------------------------------------------------

def _interp(ts: list[float], vals: list[tuple[float, float]],
            t: float) -> tuple[float, float] | None:
    i = bisect.bisect_left(ts, t)
    if i == 0 or i >= len(ts):
        return None
    t0, t1 = ts[i - 1], ts[i]
    if t1 - t0 > 0.1:
        return None
    a = (t - t0) / (t1 - t0)
    (x0, y0), (x1, y1) = vals[i - 1], vals[i]
    return (x0 + a * (x1 - x0), y0 + a * (y1 - y0))


def _stats(errs: list[float]) -> dict[str, float]:
    if not errs:
        return {"n": 0}
    s = sorted(errs)
    return {"n": len(s), "rmse": math.sqrt(sum(e * e for e in s) / len(s)),
            "median": s[len(s) // 2], "p95": s[int(0.95 * (len(s) - 1))], "max": s[-1],
            "over_100mm": sum(e > 100 for e in s) / len(s)}


def end_to_end(seconds: float) -> dict[str, Any]:
    import zmq

    from backend.world.decode import decode_detection
    from backend.world.model import WorldModel
    from sslnet.multicast import loopback_multicast_ok
    from sslpb import touchline_pb2 as tl
    from sslpb.ssl_vision_wrapper_pb2 import SSL_WrapperPacket

    if not loopback_multicast_ok():
        return {"skipped": "multicast on loopback does not work here"}
    with __import__("socket").socket() as s:
        s.bind(("127.0.0.1", 0))
        truth_port = s.getsockname()[1]
    truth_ep = f"tcp://127.0.0.1:{truth_port}"
    proc = subprocess.Popen(
        [sys.executable, "-m", "launcher", "--isolated", "--sim-arg=--false-prob=0.2",
         f"--sim-arg=--truth-pub={truth_ep}"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    ports: dict[str, Any] = {}
    url = ""
    assert proc.stdout is not None
    deadline = time.monotonic() + 40
    while time.monotonic() < deadline and not url:
        line = proc.stdout.readline()
        if not line:
            break
        if line.startswith("TOUCHLINE_PORTS "):
            ports = json.loads(line.split(" ", 1)[1])
        elif line.startswith("TOUCHLINE_READY "):
            url = line.split(" ", 1)[1].strip()
    # keep draining the launcher's stdout so it never blocks
    threading.Thread(target=lambda: [None for _ in proc.stdout or []], daemon=True).start()
    if not url:
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
        return {"skipped": "the station did not start"}
    ctx = zmq.Context()
    truth_sock = ctx.socket(zmq.SUB)
    truth_sock.setsockopt(zmq.SUBSCRIBE, b"truth")
    truth_sock.setsockopt(zmq.RCVHWM, 100000)
    truth_sock.connect(truth_ep)
    vis_sock = ctx.socket(zmq.SUB)
    vis_sock.setsockopt(zmq.SUBSCRIBE, b"vision")
    vis_sock.setsockopt(zmq.RCVHWM, 100000)
    vis_sock.connect(ports["relay_pub"])
    truths: list[dict[str, Any]] = []
    frames: list[tuple[bytes, int]] = []
    worlds: list[dict[str, Any]] = []
    stop = threading.Event()

    def poll_world() -> None:
        while not stop.is_set():
            try:
                with urllib.request.urlopen(url + "/api/world", timeout=2) as r:
                    worlds.append(json.loads(r.read()))
            except OSError:
                pass
            time.sleep(0.02)

    time.sleep(2.0)  # let the demo start moving and the world settle
    poller = threading.Thread(target=poll_world, daemon=True)
    poller.start()
    poll = zmq.Poller()
    poll.register(truth_sock, zmq.POLLIN)
    poll.register(vis_sock, zmq.POLLIN)
    t_end = time.monotonic() + seconds
    try:
        while time.monotonic() < t_end:
            for sock, _ in poll.poll(50):
                while True:
                    try:
                        topic, body = sock.recv_multipart(zmq.NOBLOCK)
                    except zmq.Again:
                        break
                    if topic == b"truth":
                        truths.append(json.loads(body))
                    else:
                        env = tl.Envelope()
                        env.ParseFromString(body)
                        frames.append((env.payload, env.receive_time_ns))
    finally:
        stop.set()
        poller.join(5)
        truth_sock.close(0)
        vis_sock.close(0)
        ctx.term()
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()

    truths.sort(key=lambda d: d["t_unix"])
    robot_truth: dict[tuple[str, int], tuple[list[float], list[tuple[float, float]]]] = {}
    ball_t: list[float] = []
    ball_v: list[tuple[float, float]] = []
    speeds: list[float] = []
    for d in truths:
        ball_t.append(d["t_unix"])
        ball_v.append((d["ball"]["x"], d["ball"]["y"]))
        for r in d["robots"]:
            k = (r["team"], r["id"])
            ts_, vs_ = robot_truth.setdefault(k, ([], []))
            ts_.append(d["t_unix"])
            vs_.append((r["x"], r["y"]))
            speeds.append(math.hypot(r["vx"], r["vy"]))
    ball_speed = [math.hypot(d["ball"]["vx"], d["ball"]["vy"]) for d in truths]

    def robot_err(team: str, rid: int, t: float, x: float, y: float) -> float | None:
        tr = robot_truth.get((team, rid))
        p = _interp(tr[0], tr[1], t) if tr else None
        return None if p is None else math.hypot(x - p[0], y - p[1])

    def ball_err(t: float, x: float, y: float) -> float | None:
        p = _interp(ball_t, ball_v, t)
        return None if p is None else math.hypot(x - p[0], y - p[1])

    # the station, as the browser sees it (/api/world: its default filter settings)
    st_robot, st_ball = [], []
    for w in worlds:
        for r in w["robots"]:
            if r["visible"]:
                e = robot_err(r["team"], r["id"], w["t_capture"] - r["age_s"], r["x"], r["y"])
                if e is not None:
                    st_robot.append(e)
        b = w.get("ball")
        if b and b["visible"]:
            e = ball_err(w["t_capture"] - b["age_s"], b["x"], b["y"])
            if e is not None:
                st_ball.append(e)
    # the same vision frames replayed through the world model with each filter kind
    decoded = []
    for payload, rx in frames:
        pkt = SSL_WrapperPacket()
        pkt.ParseFromString(payload)
        if pkt.HasField("detection"):
            decoded.append(decode_detection(pkt.detection, rx))
    replay: dict[str, Any] = {}
    for kind in FILTER_KINDS:
        m = WorldModel(filters=FilterSettings(ball=kind, robot=kind))
        r_err: list[float] = []
        b_err: list[float] = []
        t0 = time.perf_counter()
        for i, f in enumerate(decoded):
            m.update(f)
            if i % 4:
                continue  # sample the world about every 4th frame (~60 Hz)
            w = m.snapshot()
            for r in w.robots:
                if r.visible:
                    e = robot_err(r.team, r.id, r.t_seen, r.x, r.y)
                    if e is not None:
                        r_err.append(e)
            if w.ball is not None and w.ball.visible:
                e = ball_err(w.ball.t_seen, w.ball.x, w.ball.y)
                if e is not None:
                    b_err.append(e)
        replay[kind] = {"robots": _stats(r_err), "ball": _stats(b_err),
                        "cpu_s": time.perf_counter() - t0,
                        "ball_recoveries": m.ball_recoveries,
                        "ball_rejected_on_robot": m.ball_rejected_on_robot}
    return {
        "seconds": seconds, "truth_samples": len(truths), "vision_frames": len(decoded),
        "world_polls": len(worlds),
        "robot_speed_mean_mm_s": sum(speeds) / max(1, len(speeds)),
        "robot_speed_max_mm_s": max(speeds, default=0.0),
        "ball_speed_max_mm_s": max(ball_speed, default=0.0),
        "station": {"robots": _stats(st_robot), "ball": _stats(st_ball),
                    "defaults": FilterSettings().model_dump(include={"ball", "robot"})},
        "replay": replay,
    }


# -- report ---------------------------------------------------------------------------------

def _f(v: float) -> str:
    return f"{v:.1f}"


def write_readme(out: Path, res: dict[str, Any]) -> None:
    L: list[str] = []
    a = res["fig2"]
    L += ["# Vision filter experiment", "",
          "Regenerate: `.venv/bin/python -m experiments.filters.run --out docs/experiments/filters`"
          f" (seed {res['seed']}, {res['runs']} runs per synthetic case, about "
          f"{res['runtime_s']:.0f} s here).", "",
          "The filter of the URoboRus 2022 TDP (section 5.1): median of the last N = 5 "
          "measurements per coordinate, then `est = 0.95 est_prev + 0.05 median`, "
          "re-initialised after a gap (> 1 s) or a jump (> 200 mm). Implemented in "
          "`backend/filters/` (`PaperFilter`), next to `RawFilter`, `MedianFilter` and the "
          "constant-velocity Kalman filter `KalmanCV` the paper argues against.", "",
          "## (a) The paper's Fig. 2, regenerated", "",
          "![Fig. 2](fig2.svg)", "",
          "1-D signal at 60 Hz: still at 500 mm, 0.3 m/s for 2 s, still at 1100 mm; Gaussian "
          "noise 5 mm; with probability 0.2 an outlier of 100-400 mm either side. Error after "
          "0.5 s:", "",
          "| output | RMSE (mm) | max (mm) |", "|---|---|---|",
          f"| measurements | {_f(a['raw_rmse'])} | {_f(a['raw_max'])} |",
          f"| median (N=5) | {_f(a['median_rmse'])} | {_f(a['median_max'])} |",
          f"| final (median + weighted average) | {_f(a['paper_rmse'])} | {_f(a['paper_max'])} |",
          "",
          f"While still (0.5-1.5 s) the final output's error std is {a['paper_still_std']:.2f} mm "
          "against 5 mm noise: the paper's two conclusions hold (outliers removed, variance "
          "reduced). While moving, the final output lags (below).", ""]
    for block, title in (("p_out=0.2", "with outliers, p = 0.2 (200-1000 mm away)"),
                         ("p_out=0.0", "noise only")):
        L += [f"## (b) Synthetic 2-D cases, {title}", "",
              f"60 Hz, Gaussian noise {NOISE_MM:.0f} mm per coordinate, errors (Euclidean, mm) "
              "after a 0.5 s warm-up, over all runs. Kalman defaults: acceleration noise "
              "4000 mm/s^2, measurement noise 3 mm.", "",
              "| case | filter | RMSE | p95 | max |", "|---|---|---|---|---|"]
        for cname, row in res["tables"][block].items():
            for fname, s in row.items():
                L.append(f"| {cname} | {fname} | {_f(s['rmse'])} | {_f(s['p95'])} | "
                         f"{_f(s['max'])} |")
        L.append("")
    L += ["## Lag of the weighted average at constant speed", "",
          "![lag](lag.svg)", "",
          "Predicted steady-state lag = v dt w_prev / w_new + 2 v dt (the median of a ramp is "
          "2 samples old), dt = 1/60 s. Measured along the motion after 3 s, noise only:", "",
          "| speed (m/s) | filter | predicted (mm) | mean lag (mm) | max lag (mm) |",
          "|---|---|---|---|---|"]
    for r in res["tables"]["lag"]:
        L.append(f"| {r['v_mm_s'] / 1000:g} | {r['filter']} | {_f(r['predicted_mm'])} | "
                 f"{_f(r['mean_mm'])} | {_f(r['max_mm'])} |")
    L.append("")
    e = res.get("e2e", {"skipped": "run with --no-e2e"})
    L += ["## (c) End to end: the real station against fieldsim's truth", ""]
    if "skipped" in e:
        L += [f"Skipped: {e['skipped']}.", ""]
    else:
        L += [f"`launcher --isolated --sim-arg=--false-prob=0.2 --sim-arg=--truth-pub=...`: "
              f"fieldsim (4 cameras at 60 Hz, noise 2 mm, false balls p=0.2 per camera frame, "
              f"half on top of a robot), relay, backend with the blue demo driving. "
              f"{e['seconds']:.0f} s: {e['vision_frames']} detection frames, "
              f"{e['truth_samples']} truth samples, {e['world_polls']} polls of `/api/world`. "
              f"Robot speed mean {e['robot_speed_mean_mm_s']:.0f} mm/s, max "
              f"{e['robot_speed_max_mm_s']:.0f} mm/s; ball speed max "
              f"{e['ball_speed_max_mm_s']:.0f} mm/s. Error = distance between the "
              "estimate and the truth interpolated at the estimate's capture time "
              "(visible objects only).", "",
              "| source | object | samples | RMSE (mm) | median | p95 | max | > 100 mm |",
              "|---|---|---|---|---|---|---|---|"]

        def row(src: str, obj: str, s: dict[str, float]) -> str:
            if not s.get("n"):
                return f"| {src} | {obj} | 0 | | | | | |"
            return (f"| {src} | {obj} | {s['n']} | {_f(s['rmse'])} | {_f(s['median'])} | "
                    f"{_f(s['p95'])} | {_f(s['max'])} | {100 * s['over_100mm']:.2f} % |")
        d = e["station"]["defaults"]
        src = f"station `/api/world` (ball {d['ball']}, robots {d['robot']})"
        L += [row(src, "robots", e["station"]["robots"]), row(src, "ball", e["station"]["ball"])]
        for kind, r in e["replay"].items():
            L += [row(f"replay, all `{kind}`", "robots", r["robots"]),
                  row(f"replay, all `{kind}`", "ball", r["ball"])]
        L += ["", "The replay rows feed the very detection frames the station received (a "
              "second subscriber on the relay's ZeroMQ PUB) through `WorldModel` with each "
              "filter kind. Ball recoveries in the replay: "
              + ", ".join(f"{k} {r['ball_recoveries']}" for k, r in e["replay"].items())
              + "; false balls rejected inside a robot footprint: "
              + str(e["replay"]["raw"]["ball_rejected_on_robot"]) + ".", ""]
    L += adaptive_section(res["acceptance"])
    L += ["## Discussion", "", res["discussion"], ""]
    (out / "README.md").write_text("\n".join(L))


def adaptive_section(acc: dict[str, Any]) -> list[str]:
    """(d): the adaptive filter's design and its acceptance table (issue 13 section 3)."""
    sv = acc["still_velocity"]
    lg = acc["lag_2m_s"]
    ne = acc["noise_estimate"]
    L = ["## (d) One filter that fits the data: `adaptive`", "",
         "The default since it was tried in closed loop: with it, "
         "`tests/integration/test_strategy_sim.py` (the match play on fieldsim, judged on "
         "fieldsim's truth) failed 2 of 4 module runs, both in ball placement by pulling: the "
         "placer, 40-60 mm short of a ball on the goal line, backed up without it and came "
         "back, for 30 s (the same failure was seen once with `kalman`). The placer now backs "
         "up only when the robot reports the ball at its dribbler (feedback), and the module "
         "passed 4 of 4 runs with `adaptive` (and the rest of the integration tests with it). "
         "The earlier suspicion (a lagging still model feeding Algorithm 1's gain estimate) "
         "was not seen again.", "",
         "The filters above are tuned for one noise level: the Kalman filter assumes 3 mm, so "
         "at 20 mm it follows the noise, and the paper's filter is precise on a still object "
         "but lags a moving one. `adaptive` (`backend/filters/adaptive/`) needs no tuning:",
         "",
         "- **Two motion models, mixed (IMM)**: *still* (constant position: its estimate is "
         "the running mean, the most precise thing a still object allows, and its velocity is "
         "exactly zero) and *moving* (constant velocity). Model probabilities follow a Markov "
         "chain (0.03 switches/s: fewer switches, less mixing noise on a moving object) "
         "and the likelihood of each measurement; the output is the "
         "probability-weighted mix. Why an IMM rather than one Kalman filter with estimated "
         "noise: no single process noise fits a resting ball and a rolling one, and the still "
         "model is what makes a standing robot's velocity read zero instead of 50-120 mm/s.",
         "- **Measurement noise from the data**: the variance of the second differences of "
         "the measurements the filter used (z_k - z_k-1 - c (z_k-1 - z_k-2), variance "
         "(1 + (1 + c)^2 + c^2) r while the motion is smooth), averaged 1/n, then over 100 "
         "samples. Why not from the innovations (Mehra / Sage-Husa): there the model's own "
         "error leaks into r (a decelerating ball read as 8 mm noise at 2 mm); second "
         "differences do not depend on the motion model, so r and q can be told apart. "
         "While the estimate is young (fewer than 100 samples) each revision of r rescales "
         "the models' covariances by the same factor (round 3): while the data dominate "
         "them they are proportional to r, and a track begun with the guess (10 mm) below "
         "the truth (20 mm) otherwise kept a covariance 4 x too small, read its own start "
         "as large innovations, raised q and restarted on 4.5-sigma 'jumps' (round 2's slow "
         "q walk: the median q at 1 s of a straight 2 m/s run is now 3.5 mm/s^2, was 74).",
         "- **Process noise from the innovations**: the moving model's acceleration noise q "
         "is multiplied by exp(0.3 (s - 1.5)) per step, s the mean of the normalised "
         "innovation squared and of the squared running mean of the normalised innovations "
         "(a bias test over about 7 steps: a decelerating ball keeps them on one side long "
         "before their size grows), s capped at 6, q within 1 .. 20000 mm/s^2: q grows "
         "fast when the model falls behind and shrinks slowly to the smallest q the data "
         "agree with (on a straight run the filter becomes a long line fit, as the tuned "
         "Kalman filter does). "
         "A measurement a little outside the gate while no outliers are about raises q (to "
         "where it is a 3-sigma innovation, at most to q's bound) and the step is redone "
         "(round 3): under constant deceleration q had shrunk to its floor, the lag grew "
         "past the gate and each such frame restarted the track from one measurement's "
         "velocity (the bounced ball at 2 mm, 1.2 x the oracle in round 2; in 20 runs of the "
         "first second of rolling out, 7 restarted 1-4 times; now none does).",
         "- **A cruise model beside the moving one** (round 4): constant velocity with a "
         "small fixed q (10 mm/s^2, `cruise_accel_mm_s2`), weighed against the moving model "
         "by the likelihood ratio of each measurement (a two-state Markov chain, 5 switches/s) "
         "and, once all but ruled out (probability 1e-3), left to rest for 0.1 s and then "
         "restarted from the moving model's state (what an IMM's mixing would do then, for "
         "less arithmetic than mixing three models; the rest saves its cost while a robot "
         "keeps turning, and longer rests (0.25 s and more) cost the bounced ball at 2 mm "
         "its margin). Why: the estimated q is raised by a maneuver or by noise that looks "
         "like one "
         "(one 4-sigma measurement at 20 mm sets it to its bound; a track's first second, with "
         "r not yet learnt, drives it up) and decays over a second or so, and meanwhile the "
         "estimate of a straight run follows the noise: the constant-speed cells at 20 mm "
         "were at 1.10-1.125 x the oracle on seeds 7, 11 and 2022 with 40 runs (4 of 84 cells "
         "missed), and lowering q's adaptation traded them for the bounced ball (1.13-1.19). "
         "With the cruise model the straight run keeps its low-q estimate whatever q does "
         "(q set to its bound halfway through a 1 m/s run at 20 mm: 1.38 x the error over the "
         "next 1.5 s, was 1.96 x), and a bounce rules it out within a frame or two. The "
         "orientation filter (1-D) has none.",
         "- **Outliers vs maneuvers**: a measurement outside the gate (4.5 sigma) of every "
         "model that is not ruled out is an outlier when it is farther than the object can "
         "have travelled (6.5 m/s); a reachable one is a maneuver (kick, bounce) at once "
         "while the estimated outlier rate is below 0.5 % (round 3, from 2 %: one outlier "
         "sets it to 1 %, so one false detection in the last second is enough to make the "
         "next jump wait; with 2 % the second false detection of a run, two frames after "
         "the first, was taken for a kick for a frame), otherwise when the next measurement "
         "confirms it (moving away in the same direction, or moving as the track does). "
         "After a jump the old track is kept for one step and restored if the next "
         "measurement fits it better (a stray spike); until then the velocity reads as "
         "before the jump (one 5-sigma noise spike on a standing robot must not read as a "
         "5 m/s kick). Three recent rejected measurements on one line at a possible speed "
         "re-initialise there (a track started on an outlier, the ball placed elsewhere), "
         "with the same fallback: three aligned false detections took a tracked ball away "
         "for good in round 1. Round 4: a line that does not start where the object was "
         "(false detections, or a lost track) is not shown until the next measurement "
         "confirms it, and a measurement far from both tracks confirms nothing (the next one "
         "decides, up to 0.1 s, when outliers have been seen and it is twice as far as both "
         "gates: with r still small at a track's start, true measurements had been held back "
         "too): on seed 3 a resting ball at "
         "20 mm / p 0.2 was taken 500-700 mm away for four frames by three aligned false "
         "detections and a fourth one (2.3 x the oracle).",
         "- **Gating with outliers about**: once outliers have been seen (rate rho), the "
         "moving model takes a measurement only where it is likelier from it than a false "
         "detection, (1 - rho) N(d; S) > rho / area (false detections within about 1 m, "
         "`outlier_spread_mm`), and where it leaves the velocity possible (<= 1.2 x 6.5 "
         "m/s). Why: right after a jump the track's velocity comes from two measurements, "
         "its prediction is wide, and the 4.5-sigma gate alone let the next false detection "
         "in, which sent the track off at 10 m/s for several frames (the kicked and bounced "
         "misses with 20 mm noise and outliers in round 1).",
         "- **Speed**: plain float arithmetic, the axes sharing their covariances "
         "(isotropic noise), the state one list of floats unpacked per step (the output mix "
         "kept in it: read far more often than it changes); the step computes everything the "
         "correction needs that does not depend on the measurement (inverse variances, "
         "gains, corrected covariances, gates, prior odds), so a second camera's detection "
         "at the same instant (`revise`) redoes only innovations, likelihood ratio and "
         "state; the IMM mixing is written in the models' difference (a third of the "
         "arithmetic) and skipped while the object is moving for sure (probability of "
         "still at its floor); the step's constants are one tuple. The noise estimates "
         "learn once per instant, at the next step. Orientation uses a 1-D variant. "
         "`bench/world_bench.py` (CPU time, 22 robots + ball in every frame from 8 cameras): "
         "round 1 106 vs Kalman 95 us per frame; round 2 92 vs 92; round 3 90 vs 89 (best "
         "of 7 interleaved; run to run the pair moves by 1-2 us: round 2's code read 92 vs "
         "90 in the same session); round 4 103 vs 94, round 3's code 95 in the same session "
         "(best of 11 interleaved; three such sessions read +9 to +12 us): the cruise model's "
         "likelihood and state in every correction, 2.8 -> 3.6 us per 2-D step.",
         "- **How close it is** (round 1 missed 8 cells, round 2 5, round 3 none on this "
         "seed): on seeds 7, 11 and 2022 with 40 runs per cell (84 cells) round 3 missed 4 "
         "(worst 1.125, moving 1 m/s at 20 mm with outliers; moving 0.5 and 3 m/s at 20 mm, "
         "1.107); round 4 misses none, worst 1.082 (moving 1 m/s at 20 mm with outliers, seed "
         "7), then 1.081 and 1.066 (the bounced ball at 20 mm with outliers and at 2 mm, seed "
         "2022); with 20 runs on the same seeds round 3 missed 6 (worst 1.18), round 4 none "
         "(worst 1.098). On seeds 1, 2 and 3 (40 runs) round 3 missed 5, "
         "round 4 one: the bounced ball at 2 mm with outliers on seed 3 (1.88, as in round "
         "3): a few runs where the bounce comes with false detections about, so it waits "
         "for a confirmation that the next false detection spoils (four frames 65-250 mm "
         "behind). Keeping two pending jumps instead of one to confirm against was tried "
         "and made it worse elsewhere (pairs of false detections confirmed each other). "
         "The thinnest margin on this page's data is the bounced ball at 2 mm (the lag "
         "under deceleration is learnt in the first half second; the oracle has its q from "
         "the first frame).",
         "",
         "Acceptance (issue 13 section 3): RMSE (mm) over "
         "the runs, 60 Hz, warm-up 0.5 s. Scenarios and filters: "
         "`experiments/filters/acceptance.py`. *kalman tuned* is an oracle: the best of "
         f"{len(acceptance.KALMAN_GRID_Q)} x {len(acceptance.KALMAN_GRID_GATE)} Kalman "
         "filters (acceleration noise 10 .. 1e5 mm/s^2, gate none or 150 mm, the true "
         "measurement noise) chosen on the very data it is scored on. Bold: the best of raw, "
         "median, paper and tuned Kalman; criterion: adaptive <= "
         f"{acceptance.TOLERANCE:g} x that.", ""]
    L += acceptance.markdown(acc)
    L += ["", "Speed read on a still object (truth 0; mm/s after the warm-up):", "",
          "| noise | filter | RMS | p95 | max |", "|---|---|---|---|---|"]
    for n, d in sv.items():
        for f, v in d.items():
            L.append(f"| {n} | {f} | {v['rms']:.2f} | {v['p95']:.2f} | {v['max']:.1f} |")
    L += ["", "Mean lag along the motion at 2 m/s (mm; negative = ahead): "
          + "; ".join(f"{n}: Kalman {d['kalman']:.2f}, adaptive {d['adaptive']:.2f}"
                      for n, d in lg.items()) + ".", "",
          "The adaptive filter's noise estimate at the end of a still run (std, mm): "
          + "; ".join(f"{k}: " + ", ".join(f"{v:.1f}" for v in vs) for k, vs in ne.items())
          + ".", ""]
    return L


def discussion(res: dict[str, Any]) -> str:
    t = res["tables"]["p_out=0.2"]
    t0 = res["tables"]["p_out=0.0"]
    st = t["stationary"]
    cs = t["constant 1 m/s"]
    bo = t["ball bouncing off a robot (3 m/s -> 0.9 m/s back at t=1 s)"]
    P, K, KG, M = ("paper: median + weighted avg (0.05/0.95)", "Kalman CV (defaults, no gate)",
                   "Kalman CV, gate 150 mm", "median (N=5)")
    lag1 = [r for r in res["tables"]["lag"] if r["v_mm_s"] == 1000.0]
    parts = [
        f"- **Still objects, noise only**: the paper's filter is the most precise (RMSE "
        f"{_f(t0['stationary'][P]['rmse'])} mm vs raw {_f(t0['stationary']['raw']['rmse'])}, "
        f"median {_f(t0['stationary'][M]['rmse'])}, Kalman {_f(t0['stationary'][K]['rmse'])} mm):"
        " the 0.05 weight reduces the noise variance by about w/(2-w). This is the case the "
        "paper designed it for.",
        f"- **Still objects, outliers p=0.2 in 2-D**: the per-coordinate median of 5 lets an "
        "outlier through when 3 of the 5 fall on one side (a few % of windows), and the paper "
        "filter's jump rule then re-initialises *to* that outlier: RMSE "
        f"{_f(st[P]['rmse'])} mm, max {_f(st[P]['max'])} mm (median {_f(st[M]['rmse'])} / "
        f"{_f(st[M]['max'])}); p95 is small ({_f(st[P]['p95'])} mm). The gated Kalman "
        f"filter: {_f(st[KG]['rmse'])} / {_f(st[KG]['max'])} mm, but note these synthetic "
        "outliers are all >= 200 mm away, which a 150 mm gate catches by construction; the "
        f"ungated Kalman filter is ruined ({_f(st[K]['rmse'])} mm).",
        f"- **Moving objects**: the weighted average lags. At 1 m/s the steady-state lag would be "
        f"{_f(lag1[1]['predicted_mm'])} mm, more than the 200 mm jump threshold, so with the "
        "paper's defaults the filter re-initialises again and again (a saw-tooth between about "
        f"the median delay and 200 mm; mean lag {_f(lag1[0]['mean_mm'])} mm). At 1 m/s its RMSE "
        f"is {_f(cs[P]['rmse'])} mm against {_f(cs[KG]['rmse'])} mm for the gated Kalman filter. "
        "A robot controller fed with that lag overshoots; the lag grows linearly with speed and "
        "inversely with the camera rate (at 75 Hz it is 4/5 of the 60 Hz value).",
        f"- **Bounce** (abrupt turn): the paper's claim that the Kalman filter handles a bounce "
        f"badly is true only in a narrow sense: the CV Kalman overshoots for a few frames after "
        f"the turn (max {_f(bo[KG]['max'])} mm gated), but the paper filter's lag is worse over "
        f"the whole run (RMSE {_f(bo[P]['rmse'])} vs {_f(bo[KG]['rmse'])} mm, max "
        f"{_f(bo[P]['max'])} vs {_f(bo[KG]['max'])} mm).",
        "- **Outliers in the station**: in the "
        "world model most outliers never reach a filter: robots are identified by id, and "
        "false balls are rejected by the robot-footprint test and by association to the "
        "predicted ball before filtering.",
        "- **Choice of defaults**: `FilterSettings()` uses `adaptive` for the ball and robots "
        "(section (d): it needs no tuning for the noise level, is as precise as the paper's "
        "filter on a still object and does not lag a moving one, and gives a velocity that "
        "reads zero on a still robot); `kalman`, `paper`, `median` and `raw` stay selectable "
        "per object class and per robot. The median filter alone is a cheap, lag-light (2 "
        "samples) outlier remover.",
    ]
    e = res.get("e2e", {})
    if "replay" in e:
        rp = e["replay"]
        parts.append(
            "- **End to end**: robots: raw " + _f(rp["raw"]["robots"].get("rmse", 0)) +
            " mm RMSE, median " + _f(rp["median"]["robots"].get("rmse", 0)) + ", paper " +
            _f(rp["paper"]["robots"].get("rmse", 0)) + ", Kalman " +
            _f(rp["kalman"]["robots"].get("rmse", 0)) + ", adaptive " +
            _f(rp.get("adaptive", {}).get("robots", {}).get("rmse", 0)) + " mm; ball: raw " +
            _f(rp["raw"]["ball"].get("rmse", 0)) + ", paper " +
            _f(rp["paper"]["ball"].get("rmse", 0)) + ", Kalman " +
            _f(rp["kalman"]["ball"].get("rmse", 0)) + ", adaptive " +
            _f(rp.get("adaptive", {}).get("ball", {}).get("rmse", 0)) +
            " mm. fieldsim's noise is only 2 mm, so "
            "the raw robot error is already small; what matters is lag (paper) and whether "
            "false balls get through (the '> 100 mm' column). The station row is what the "
            "browser sees; it is sampled at poll time, so it includes the age of the estimate "
            "only through the capture time used for the truth lookup.")
        if e["ball_speed_max_mm_s"] < 100:
            parts.append("- **Caveat**: the ball did not move in this end-to-end run (nobody "
                         "kicks in the demo), so the end-to-end ball rows measure precision on a "
                         "still ball and the rejection of false balls (p=0.2), not tracking; the "
                         "moving-ball behaviour is in the synthetic tables and the tests.")
    return "\n".join(parts)


def main() -> int:
    ap = argparse.ArgumentParser(prog="python -m experiments.filters.run", description=__doc__)
    ap.add_argument("--out", default="docs/experiments/filters")
    ap.add_argument("--seed", type=int, default=2022)
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--e2e-seconds", type=float, default=15.0)
    ap.add_argument("--no-e2e", action="store_true")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.monotonic()
    res: dict[str, Any] = {"seed": a.seed, "runs": a.runs}
    res["fig2"] = fig2(out, a.seed)
    res["tables"] = tables(a.seed, a.runs)
    res["acceptance"] = acceptance.run_all(a.seed, a.runs)
    lag_figure(out, a.seed)
    print("synthetic done", f"{time.monotonic() - t0:.1f} s", flush=True)  # noqa: T201
    if not a.no_e2e:
        res["e2e"] = end_to_end(a.e2e_seconds)
        print("end to end done", f"{time.monotonic() - t0:.1f} s", flush=True)  # noqa: T201
    res["runtime_s"] = time.monotonic() - t0
    res["discussion"] = discussion(res)
    (out / "results.json").write_text(json.dumps(res, indent=1, default=str))
    write_readme(out, res)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
