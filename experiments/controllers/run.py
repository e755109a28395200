"""The paper's comparison (URoboRus 2022, section 5.2), reproduced on fieldsim in-process.

All 6 blue robots drive the same 3 m at the same moment, there and back and there again (3 legs,
so the estimate of C carries over), under Algorithm 1, Algorithm 2 and the proportional
baseline, with generation-1 robots (unequal gains C) and generation-2 robots (C = 1). Writes SVG
plots, ``results.md`` (tables) and ``results.json`` into ``--out``.

    .venv/bin/python -m experiments.controllers.run --out docs/experiments/controllers
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path
from typing import Any

from backend.control.params import ALGORITHMS, AlgorithmName, ControllerParams
from experiments.controllers.harness import Case, CaseResult, LegMetrics, leg_metrics, run_case
from experiments.controllers.svgplot import HLine, Plot, Series, render

GEN1_GAINS = [0.6, 0.76, 0.92, 1.08, 1.24, 1.4]
TITLES = {"algorithm1": "Algorithm 1", "algorithm2": "Algorithm 2", "proportional": "Proportional"}


def _f(v: float | None, nd: int = 2) -> str:
    return "never" if v is None else f"{v:.{nd}f}"


def _summary(m: LegMetrics) -> dict[str, Any]:
    arr = [a for a in m.arrival_s if a is not None]
    settle = m.settle_s
    return {
        "arrival_s": m.arrival_s,
        "settle_s": settle,
        "overshoot_mm": m.overshoot_mm,
        "final_error_mm": m.final_error_mm,
        "arrival_spread_s": m.arrival_spread_s,
        "arrival_mean_s": statistics.fmean(arr) if arr else None,
        "settle_max_s": None if any(s is None for s in settle)
        else max(s for s in settle if s is not None),
        "overshoot_max_mm": max(m.overshoot_mm),
        "final_error_max_mm": max(m.final_error_mm),
    }


def plot_case(res: CaseResult, path: Path) -> None:
    case = res.case
    series = []
    for tr in res.traces:
        series.append(Series(f"blue {tr.rid}, C={tr.gain:.2f}", tr.t,
                             [x - res.start_x for x in tr.x]))
    if case.algorithm == "algorithm1":
        tr = res.traces[0]
        ref = []
        for t, r in zip(tr.tc, tr.ref_x, strict=True):
            leg = min(case.legs - 1, int(t / case.leg_s))
            ref.append(r if leg % 2 == 0 else case.distance_m - r)
        series.append(Series("x*(t), blue 0", tr.tc, ref, color="#000000", dash="5 4",
                             width=1.2))
    gen = f"generation {case.generation}" + (" (C spread)" if case.generation == 1 else
                                             " (C = 1)")
    plot = Plot(f"{TITLES[case.algorithm]}, {gen}: position along the 3 m line",
                "time (s)", "distance from A (m)", series,
                [HLine(case.distance_m, "B"), HLine(0.0, "A")])
    path.write_text(render(plot))


def plot_c(res: CaseResult, path: Path) -> None:
    series = [Series(f"blue {tr.rid}, true C={tr.gain:.2f}", tr.tc, tr.c_est)
              for tr in res.traces]
    hl = [HLine(tr.gain, "") for tr in res.traces]
    plot = Plot("Algorithm 1, generation 1: online estimate of C", "time (s)",
                "estimated C (dimensionless)", series, hl)
    path.write_text(render(plot))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    ap.add_argument("--out", type=Path, default=Path("docs/experiments/controllers"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--seeds", type=int, default=5, help="seeds 1..N for the robustness table")
    ap.add_argument("--latency", type=float, default=0.03, help="command latency, s")
    args = ap.parse_args(argv)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    results: dict[str, Any] = {"seed": args.seed, "latency_s": args.latency,
                               "gen1_gains": GEN1_GAINS, "cases": {}, "seeds": {},
                               "variants": {}}
    lines: list[str] = []
    lines.append(f"Seed {args.seed}, command latency {args.latency * 1000:.0f} ms, controllers "
                 "at 60 Hz on raw noisy vision (4 cameras, 2 mm noise, 1 % misses), legs of "
                 "8 s: leg 1 A->B with the initial C estimate, leg 3 A->B after two legs of "
                 "learning. Arrival = first time within 20 mm of B; settle = within 20 mm "
                 "from then to the end of the leg; overshoot = furthest point past B along the "
                 "line; final error = distance to B at the end of the leg.\n")
    lines.append("| algorithm | robots | leg | arrival spread (s) | mean arrival (s) | "
                 "slowest settle (s) | max overshoot (mm) | max final error (mm) |")
    lines.append("|---|---|---|---|---|---|---|---|")
    per_robot: list[str] = []
    for alg in ALGORITHMS:
        for gen in (1, 2):
            case = Case(alg, gen, GEN1_GAINS if gen == 1 else None, seed=args.seed,
                        latency_s=args.latency)
            res = run_case(case)
            name = f"{alg}-gen{gen}"
            plot_case(res, out / f"x_{name}.svg")
            if alg == "algorithm1" and gen == 1:
                plot_c(res, out / "c_estimate_algorithm1-gen1.svg")
            legs = {}
            for leg in range(case.legs):
                s = _summary(leg_metrics(res, leg))
                legs[leg] = s
                if leg in (0, case.legs - 1):
                    lines.append(
                        f"| {TITLES[alg]} | gen {gen} | {leg + 1} | {_f(s['arrival_spread_s'])} "
                        f"| {_f(s['arrival_mean_s'])} | {_f(s['settle_max_s'])} "
                        f"| {s['overshoot_max_mm']:.0f} | {s['final_error_max_mm']:.1f} |")
            last = legs[case.legs - 1]
            per_robot.append(
                f"| {TITLES[alg]} | gen {gen} | "
                + " | ".join(f"{_f(a)} / {o:.0f}" for a, o in
                             zip(last["arrival_s"], last["overshoot_mm"], strict=True)) + " |")
            results["cases"][name] = {
                "legs": legs,
                "c_estimate_end": [tr.c_est[-1] for tr in res.traces],
                "true_c": [tr.gain for tr in res.traces],
                "controller_us_per_tick": res.controller_s / max(1, res.ticks) * 1e6,
            }
    lines.append("")
    lines.append("Per robot, leg 3: arrival (s) / overshoot (mm); robots blue 0..5 with C = "
                 + ", ".join(f"{c:.2f}" for c in GEN1_GAINS) + " in generation 1.\n")
    lines.append("| algorithm | robots | " + " | ".join(f"blue {i}" for i in range(6)) + " |")
    lines.append("|---|---|" + "---|" * 6)
    lines.extend(per_robot)
    lines.append("")
    c_line = results["cases"]["algorithm1-gen1"]
    lines.append("Algorithm 1, generation 1, estimate of C at the end (true value): "
                 + ", ".join(f"{e:.3f} ({c:.2f})" for e, c in
                             zip(c_line["c_estimate_end"], c_line["true_c"], strict=True))
                 + "\n")

    # robustness over seeds: arrival spread in leg 1 and leg 3
    lines.append(f"Arrival spread (s) over seeds 1..{args.seeds} (vision noise and camera "
                 "phases change with the seed; the gains do not): min / median / max.\n")
    lines.append("| algorithm | robots | leg 1 | leg 3 | max overshoot leg 3 (mm) |")
    lines.append("|---|---|---|---|---|")
    for alg in ALGORITHMS:
        for gen in (1, 2):
            sp1: list[float] = []
            sp3: list[float] = []
            ov3: list[float] = []
            for seed in range(1, args.seeds + 1):
                res = run_case(Case(alg, gen, GEN1_GAINS if gen == 1 else None, seed=seed,
                                    latency_s=args.latency))
                m1, m3 = leg_metrics(res, 0), leg_metrics(res, 2)
                sp1.append(m1.arrival_spread_s if m1.arrival_spread_s is not None else
                           float("inf"))
                sp3.append(m3.arrival_spread_s if m3.arrival_spread_s is not None else
                           float("inf"))
                ov3.append(max(m3.overshoot_mm))
            results["seeds"][f"{alg}-gen{gen}"] = {"leg1": sp1, "leg3": sp3, "overshoot3": ov3}

            def mmm(v: list[float]) -> str:
                return f"{min(v):.2f} / {statistics.median(v):.2f} / {max(v):.2f}"

            lines.append(f"| {TITLES[alg]} | gen {gen} | {mmm(sp1)} | {mmm(sp3)} | "
                         f"{min(ov3):.0f} .. {max(ov3):.0f} |")
    lines.append("")

    # sensitivity of Algorithm 1 (generation 1, leg 3): reference acceleration and latency
    lines.append("Algorithm 1 sensitivity (generation 1, seed "
                 f"{args.seed}, leg 3).\n")
    lines.append("| variant | arrival spread (s) | mean arrival (s) | slowest settle (s) | "
                 "max overshoot (mm) |")
    lines.append("|---|---|---|---|---|")
    base = ControllerParams()
    variants: list[tuple[str, ControllerParams, float, AlgorithmName]] = [
        ("w = 3 m/s^2, latency 30 ms (default)", base, args.latency, "algorithm1"),
        ("w = 2 m/s^2, latency 30 ms", base.model_copy(update={
            "algorithm1": base.algorithm1.model_copy(update={"w_mps2": 2.0})}),
         args.latency, "algorithm1"),
        ("w = 3 m/s^2, latency 0 ms", base, 0.0, "algorithm1"),
        ("w = 3 m/s^2, K = 1, latency 30 ms", base.model_copy(update={
            "algorithm1": base.algorithm1.model_copy(update={"k_per_s": 1.0})}),
         args.latency, "algorithm1"),
    ]
    for label, params, lat, alg in variants:
        res = run_case(Case(alg, 1, GEN1_GAINS, seed=args.seed, latency_s=lat,
                            params=params))
        s = _summary(leg_metrics(res, 2))
        results["variants"][label] = s
        lines.append(f"| {label} | {_f(s['arrival_spread_s'])} | {_f(s['arrival_mean_s'])} | "
                     f"{_f(s['settle_max_s'])} | {s['overshoot_max_mm']:.0f} |")
    lines.append("")
    elapsed = time.perf_counter() - t_start
    results["runtime_s"] = elapsed
    lines.append(f"Runtime of the whole experiment: {elapsed:.1f} s.")
    (out / "results.md").write_text("\n".join(lines) + "\n")
    (out / "results.json").write_text(json.dumps(results, indent=1))
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
