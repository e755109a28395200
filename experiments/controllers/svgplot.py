"""A small SVG line-plot writer (matplotlib is not installed): axes with "nice" ticks, grid,
axis labels with units, a title and a legend. Pure: ``line_plot(...)`` returns the SVG text."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from xml.sax.saxutils import escape

PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf", "#000000")


@dataclass
class Series:
    label: str
    xs: Sequence[float]
    ys: Sequence[float]
    color: str | None = None
    dash: str | None = None  # e.g. "4 3"
    width: float = 1.6


@dataclass
class HLine:
    y: float
    label: str = ""
    color: str = "#555555"


@dataclass
class Plot:
    title: str
    x_label: str
    y_label: str
    series: list[Series] = field(default_factory=list)
    hlines: list[HLine] = field(default_factory=list)
    width: int = 760
    height: int = 420
    x_range: tuple[float, float] | None = None
    y_range: tuple[float, float] | None = None


def nice_ticks(lo: float, hi: float, target: int = 6) -> list[float]:
    """Round tick values (1, 2, 5 x 10^n steps) covering [lo, hi]."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return []
    if hi <= lo:
        hi = lo + 1.0
    raw = (hi - lo) / max(1, target)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = mag
    for m in (1.0, 2.0, 2.5, 5.0, 10.0):
        if raw <= m * mag:
            step = m * mag
            break
    start = math.ceil(lo / step - 1e-9) * step
    ticks = []
    v = start
    while v <= hi + step * 1e-9:
        ticks.append(0.0 if abs(v) < step * 1e-9 else v)
        v += step
    return ticks


def _fmt(v: float) -> str:
    if abs(v) >= 1000 or v == int(v):
        return f"{v:.0f}"
    s = f"{v:.3f}".rstrip("0").rstrip(".")
    return s


def render(plot: Plot) -> str:
    W, H = plot.width, plot.height
    left, right, top, bottom = 70, 170, 40, 55
    pw, ph = W - left - right, H - top - bottom
    xs = [x for s in plot.series for x in s.xs if math.isfinite(x)]
    ys = [y for s in plot.series for y in s.ys if math.isfinite(y)]
    ys += [h.y for h in plot.hlines]
    x0, x1 = plot.x_range or ((min(xs), max(xs)) if xs else (0.0, 1.0))
    y0, y1 = plot.y_range or ((min(ys), max(ys)) if ys else (0.0, 1.0))
    if y1 <= y0:
        y0, y1 = y0 - 0.5, y1 + 0.5
    if x1 <= x0:
        x1 = x0 + 1.0
    if plot.y_range is None:
        pad = 0.05 * (y1 - y0)
        y0, y1 = y0 - pad, y1 + pad

    def sx(x: float) -> float:
        return left + (x - x0) / (x1 - x0) * pw

    def sy(y: float) -> float:
        return top + ph - (y - y0) / (y1 - y0) * ph

    out = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
        f'viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">',
        f'<rect width="{W}" height="{H}" fill="white"/>',
        f'<text x="{left + pw / 2:.1f}" y="22" text-anchor="middle" font-size="15" '
        f'font-weight="bold">{escape(plot.title)}</text>',
    ]
    for t in nice_ticks(x0, x1, 8):
        X = sx(t)
        out.append(f'<line x1="{X:.1f}" y1="{top}" x2="{X:.1f}" y2="{top + ph}" '
                   'stroke="#e5e5e5"/>')
        out.append(f'<line x1="{X:.1f}" y1="{top + ph}" x2="{X:.1f}" y2="{top + ph + 5}" '
                   'stroke="black"/>')
        out.append(f'<text x="{X:.1f}" y="{top + ph + 18}" text-anchor="middle">{_fmt(t)}</text>')
    for t in nice_ticks(y0, y1, 6):
        Y = sy(t)
        out.append(f'<line x1="{left}" y1="{Y:.1f}" x2="{left + pw}" y2="{Y:.1f}" '
                   'stroke="#e5e5e5"/>')
        out.append(f'<line x1="{left - 5}" y1="{Y:.1f}" x2="{left}" y2="{Y:.1f}" stroke="black"/>')
        out.append(f'<text x="{left - 8}" y="{Y + 4:.1f}" text-anchor="end">{_fmt(t)}</text>')
    out.append(f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" '
               'stroke="black"/>')
    out.append(f'<text x="{left + pw / 2:.1f}" y="{H - 12}" text-anchor="middle">'
               f'{escape(plot.x_label)}</text>')
    out.append(f'<text transform="translate(18 {top + ph / 2:.1f}) rotate(-90)" '
               f'text-anchor="middle">{escape(plot.y_label)}</text>')
    out.append(f'<clipPath id="plotarea"><rect x="{left}" y="{top}" width="{pw}" '
               f'height="{ph}"/></clipPath>')
    for h in plot.hlines:
        Y = sy(h.y)
        out.append(f'<line x1="{left}" y1="{Y:.1f}" x2="{left + pw}" y2="{Y:.1f}" '
                   f'stroke="{h.color}" stroke-dasharray="2 3"/>')
        if h.label:
            out.append(f'<text x="{left + pw - 4}" y="{Y - 4:.1f}" text-anchor="end" '
                       f'fill="{h.color}">{escape(h.label)}</text>')
    legend_y = top + 8
    for i, s in enumerate(plot.series):
        color = s.color or PALETTE[i % len(PALETTE)]
        pts = " ".join(f"{sx(x):.1f},{sy(y):.1f}" for x, y in zip(s.xs, s.ys, strict=True)
                       if math.isfinite(x) and math.isfinite(y))
        dash = f' stroke-dasharray="{s.dash}"' if s.dash else ""
        if pts:
            out.append(f'<polyline clip-path="url(#plotarea)" fill="none" stroke="{color}" '
                       f'stroke-width="{s.width}"{dash} points="{pts}"/>')
        if s.label:
            lx = left + pw + 12
            out.append(f'<line x1="{lx}" y1="{legend_y:.1f}" x2="{lx + 24}" y2="{legend_y:.1f}" '
                       f'stroke="{color}" stroke-width="{max(2.0, s.width)}"{dash}/>')
            out.append(f'<text x="{lx + 30}" y="{legend_y + 4:.1f}">{escape(s.label)}</text>')
            legend_y += 18
    out.append("</svg>")
    return "\n".join(out) + "\n"
