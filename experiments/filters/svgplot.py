"""A tiny SVG line/scatter plot writer (no dependencies): axes, ticks, labels, legend."""

from __future__ import annotations

import math
from dataclasses import dataclass
from html import escape


@dataclass
class Series:
    name: str
    xs: list[float]
    ys: list[float]
    color: str
    style: str = "line"  # "line" or "dots"
    width: float = 1.5


def nice_ticks(lo: float, hi: float, n: int = 6) -> list[float]:
    if hi <= lo:
        hi = lo + 1.0
    raw = (hi - lo) / n
    mag = 10 ** math.floor(math.log10(raw))
    step = min((m * mag for m in (1, 2, 2.5, 5, 10) if m * mag >= raw), default=10 * mag)
    first = math.ceil(lo / step) * step
    ticks = []
    v = first
    while v <= hi + 1e-9 * step:
        ticks.append(round(v, 10))
        v += step
    return ticks


def _fmt(v: float) -> str:
    return f"{v:g}" if abs(v) < 1e5 else f"{v:.2e}"


def line_plot(series: list[Series], title: str, xlabel: str, ylabel: str,
              width: int = 960, height: int = 460,
              ylim: tuple[float, float] | None = None) -> str:
    ml, mt, mb = 80, 40, 60
    mr = 60 + int(7.2 * max(len(s.name) for s in series))
    width += mr - 190
    pw, ph = width - ml - mr, height - mt - mb
    xs = [x for s in series for x in s.xs]
    ys = [y for s in series for y in s.ys]
    x0, x1 = min(xs), max(xs)
    y0, y1 = ylim if ylim else (min(ys), max(ys))
    pad = 0.04 * (y1 - y0 or 1.0)
    if not ylim:
        y0, y1 = y0 - pad, y1 + pad

    def px(x: float) -> float:
        return ml + (x - x0) / ((x1 - x0) or 1.0) * pw

    def py(y: float) -> float:
        return mt + ph - (y - y0) / ((y1 - y0) or 1.0) * ph

    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="13">',
           f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{ml + pw / 2}" y="24" text-anchor="middle" font-size="16">'
           f'{escape(title)}</text>']
    for t in nice_ticks(x0, x1):
        X = px(t)
        out.append(f'<line x1="{X:.1f}" y1="{mt}" x2="{X:.1f}" y2="{mt + ph}" stroke="#e5e5e5"/>')
        out.append(f'<line x1="{X:.1f}" y1="{mt + ph}" x2="{X:.1f}" y2="{mt + ph + 5}" '
                   'stroke="black"/>')
        out.append(f'<text x="{X:.1f}" y="{mt + ph + 20}" text-anchor="middle">{_fmt(t)}</text>')
    for t in nice_ticks(y0, y1):
        Y = py(t)
        out.append(f'<line x1="{ml}" y1="{Y:.1f}" x2="{ml + pw}" y2="{Y:.1f}" stroke="#e5e5e5"/>')
        out.append(f'<line x1="{ml - 5}" y1="{Y:.1f}" x2="{ml}" y2="{Y:.1f}" stroke="black"/>')
        out.append(f'<text x="{ml - 8}" y="{Y + 4:.1f}" text-anchor="end">{_fmt(t)}</text>')
    out.append(f'<rect x="{ml}" y="{mt}" width="{pw}" height="{ph}" fill="none" stroke="black"/>')
    out.append(f'<text x="{ml + pw / 2}" y="{height - 15}" text-anchor="middle">'
               f'{escape(xlabel)}</text>')
    out.append(f'<text x="20" y="{mt + ph / 2}" text-anchor="middle" '
               f'transform="rotate(-90 20 {mt + ph / 2})">{escape(ylabel)}</text>')
    out.append(f'<clipPath id="plot"><rect x="{ml}" y="{mt}" width="{pw}" height="{ph}"/>'
               '</clipPath><g clip-path="url(#plot)">')
    for s in series:
        if s.style == "dots":
            for x, y in zip(s.xs, s.ys, strict=True):
                out.append(f'<circle cx="{px(x):.1f}" cy="{py(y):.1f}" r="2.2" fill="{s.color}"/>')
        else:
            pts = " ".join(f"{px(x):.1f},{py(y):.1f}" for x, y in zip(s.xs, s.ys, strict=True))
            out.append(f'<polyline points="{pts}" fill="none" stroke="{s.color}" '
                       f'stroke-width="{s.width}"/>')
    out.append("</g>")
    lx, ly = ml + pw + 15, mt + 10
    for i, s in enumerate(series):
        y = ly + 22 * i
        if s.style == "dots":
            out.append(f'<circle cx="{lx + 12}" cy="{y}" r="3" fill="{s.color}"/>')
        else:
            out.append(f'<line x1="{lx}" y1="{y}" x2="{lx + 24}" y2="{y}" stroke="{s.color}" '
                       f'stroke-width="{max(2.0, s.width)}"/>')
        out.append(f'<text x="{lx + 32}" y="{y + 4}">{escape(s.name)}</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"
