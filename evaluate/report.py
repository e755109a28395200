"""A report on disk: ``report.json`` (everything) and ``report.html`` (one self-contained page:
tables and inline SVG plots, no script, no style or font from elsewhere), beside the runs'
logs in ``runs/``."""

from __future__ import annotations

import html
import json
import math
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any

REPORT_JSON = "report.json"
REPORT_HTML = "report.html"


def write_report(out: Path, report: dict[str, Any]) -> tuple[Path, Path]:
    """Both files, each written whole (a temporary file renamed) so a reader never sees half."""
    out.mkdir(parents=True, exist_ok=True)
    j = out / REPORT_JSON
    h = out / REPORT_HTML
    _atomic(j, json.dumps(report, indent=1, sort_keys=False, allow_nan=False).encode())
    _atomic(h, render_html(report).encode())
    return j, h


def _atomic(path: Path, data: bytes) -> None:
    fd, tmp = tempfile.mkstemp(prefix=path.name, dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def read_report(folder: Path) -> dict[str, Any]:
    data = json.loads((folder / REPORT_JSON).read_text(encoding="utf-8"))
    if not isinstance(data, dict):
        raise ValueError("not a report")
    return data


# -- HTML -------------------------------------------------------------------------------------

_CSS = """
body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;max-width:1100px}
h1{font-size:22px}h2{font-size:17px;margin-top:28px}
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:3px 8px;
text-align:left;vertical-align:top}th{background:#f2f2f2}
.pass{color:#17632a;font-weight:600}.fail{color:#a4161a;font-weight:600}
.small{color:#666;font-size:12px}.verdict{padding:6px 10px;background:#f7f7e8;
border-left:4px solid #b5a300;display:inline-block}
"""


def _e(v: Any) -> str:
    return html.escape(str(v))


def _pct(r: dict[str, Any] | None) -> str:
    if not r or r.get("rate") is None:
        return "-"
    return (f"{100 * r['rate']:.0f} % <span class=small>({r['k']}/{r['n']}; 95 % "
            f"{100 * r['low']:.0f}-{100 * r['high']:.0f} %)</span>")


def _pf(ok: bool) -> str:
    return '<span class=pass>pass</span>' if ok else '<span class=fail>fail</span>'


def _bars(rows: Sequence[tuple[str, float, float, float]], width: int = 640) -> str:
    """Horizontal bars of rates 0..1 with their intervals as whiskers (inline SVG)."""
    if not rows:
        return ""
    label_w, bar_w, h = 220, width - 240, 18
    height = h * len(rows) + 24
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'role="img" font-size="11">']
    for i, (label, v, lo, hi) in enumerate(rows):
        y = i * h + 4
        out.append(f'<text x="0" y="{y + 12}">{_e(label[:34])}</text>')
        if math.isfinite(v):
            out.append(f'<rect x="{label_w}" y="{y + 2}" width="{bar_w * v:.1f}" height="12" '
                       f'fill="{"#3a8d4f" if v >= 0.999 else "#c9a227" if v > 0 else "#b33"}"/>')
            out.append(f'<line x1="{label_w + bar_w * lo:.1f}" x2="{label_w + bar_w * hi:.1f}" '
                       f'y1="{y + 8}" y2="{y + 8}" stroke="#222"/>')
    base = h * len(rows) + 8
    for f in (0.0, 0.25, 0.5, 0.75, 1.0):
        x = label_w + bar_w * f
        out.append(f'<line x1="{x}" x2="{x}" y1="0" y2="{base}" stroke="#ddd"/>')
        out.append(f'<text x="{x - 8}" y="{base + 12}">{int(f * 100)}%</text>')
    out.append("</svg>")
    return "".join(out)


def _columns(values: Sequence[float], labels: Sequence[str], width: int = 640) -> str:
    """Vertical bars around zero (a goal difference per match)."""
    if not values:
        return ""
    top = max(1.0, max(abs(v) for v in values))
    h, mid = 120, 60
    bw = max(2.0, min(24.0, (width - 40) / len(values)))
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{h + 20}" '
           f'font-size="10"><line x1="30" x2="{width}" y1="{mid}" y2="{mid}" stroke="#999"/>',
           f'<text x="0" y="{mid - 50}">+{top:g}</text><text x="0" y="{mid + 56}">-{top:g}'
           f'</text>']
    for i, v in enumerate(values):
        x = 34 + i * bw
        bh = abs(v) / top * 50
        y = mid - bh if v > 0 else mid
        colour = "#3a8d4f" if v > 0 else "#b33" if v < 0 else "#999"
        out.append(f'<rect x="{x:.1f}" y="{y:.1f}" width="{bw - 1:.1f}" '
                   f'height="{max(bh, 1):.1f}" fill="{colour}"><title>{_e(labels[i])}: '
                   f'{v:+g}</title></rect>')
    out.append("</svg>")
    return "".join(out)


def _suite_html(s: dict[str, Any], runs: Sequence[dict[str, Any]]) -> list[str]:
    out = ["<h2>Scenarios</h2>", _bars([(x["scenario"], x["pass_rate"]["rate"] or 0.0,
                                         x["pass_rate"]["low"], x["pass_rate"]["high"])
                                        for x in s["scenarios"]])]
    out.append("<table><tr><th>scenario</th><th>runs</th><th>passed</th><th>score</th>"
               "<th>failed runs</th></tr>")
    for x in s["scenarios"]:
        out.append(f"<tr><td>{_e(x['title'])}<div class=small>{_e(x['scenario'])}</div></td>"
                   f"<td>{x['runs']}</td><td>{_pct(x['pass_rate'])}</td>"
                   f"<td>{x['score']:.2f}</td><td>{_e(', '.join(x['failed_runs'][:10]))}</td></tr>")
    out.append("</table><h2>Runs</h2><table><tr><th>run</th><th>seed</th><th>result</th>"
               "<th>score</th><th>checks</th><th>log</th></tr>")
    for r in runs:
        checks = "<br>".join(f"{_pf(c['passed'])} {_e(c['label'])}: {_e(c['detail'])}"
                             for c in r.get("checks", []))
        if r.get("error"):
            checks = f"<span class=fail>error</span> {_e(str(r['error']).splitlines()[0])}"
        log = Path(r["log"]).name if r.get("log") else ""
        out.append(f"<tr><td>{_e(r['name'])}</td><td>{r.get('seed', '')}</td>"
                   f"<td>{_pf(bool(r.get('passed')))}</td><td>{float(r.get('score') or 0):.2f}"
                   f"</td><td>{checks}</td><td class=small>{_e(log)}</td></tr>")
    out.append("</table>")
    return out


def _matches_html(m: dict[str, Any], runs: Sequence[dict[str, Any]]) -> list[str]:
    a, b = m["a"], m["b"]
    out = [f"<h2>{_e(a)} against {_e(b)}</h2>",
           f"<p class=verdict>{_e(m['difference']['verdict'])}</p>",
           "<table><tr><th>played</th><th>wins</th><th>draws</th><th>losses</th>"
           f"<th>{_e(a)} win rate</th><th>share of decided</th><th>goal difference</th></tr>",
           f"<tr><td>{m['played']}</td><td>{m['win']}</td><td>{m['draw']}</td>"
           f"<td>{m['loss']}</td><td>{_pct(m['win_rate'])}</td>"
           f"<td>{_pct(m['decided_share'])}</td><td>{_gd(m['goal_difference'])}</td></tr>"
           "</table>"]
    gds, labels = [], []
    for r in runs:
        if r.get("error") or "score" not in r:
            continue
        colour = "blue" if r["blue"] == a else "yellow"
        other = "yellow" if colour == "blue" else "blue"
        gds.append(float(r["score"][colour] - r["score"][other]))
        labels.append(r["name"])
    out.append(f"<p class=small>goal difference of {_e(a)} per match</p>")
    out.append(_columns(gds, labels))
    out.append("<table><tr><th>match</th><th>seed</th><th>blue</th><th>yellow</th>"
               "<th>score</th><th>events</th><th>violations</th><th>log</th></tr>")
    for r in runs:
        res = r.get("result") or {}
        score = r.get("score") or {}
        ev = ", ".join(f"{k} {v}" for k, v in sorted((res.get("events") or {}).items()))
        viol = []
        for team, t in (res.get("teams") or {}).items():
            n = sum(v["count"] for v in t.get("violations", {}).values())
            viol.append(f"{team} {n}")
        log = Path(r["log"]).name if r.get("log") else ""
        err = f" <span class=fail>{_e(str(r['error']).splitlines()[0])}</span>" \
            if r.get("error") else ""
        out.append(f"<tr><td>{_e(r['name'])}{err}</td><td>{r.get('seed')}</td>"
                   f"<td>{_e(r['blue'])}</td><td>{_e(r['yellow'])}</td>"
                   f"<td>{score.get('blue', '-')} : {score.get('yellow', '-')}</td>"
                   f"<td>{_e(ev)}</td><td>{_e(', '.join(viol))}</td>"
                   f"<td class=small>{_e(log)}</td></tr>")
    out.append("</table>")
    return out


def _gd(g: dict[str, Any]) -> str:
    if g.get("mean") is None:
        return "-"
    return (f"{g['mean']:+.2f} <span class=small>(95 % {g['low']:+.2f} to {g['high']:+.2f})"
            f"</span>")


def _class_html(rep: dict[str, Any]) -> list[str]:
    grades = rep["grades"]
    exercises = rep["exercises"]
    out = ["<h2>Grades</h2><table><tr><th>student</th><th>total</th>"]
    out += [f"<th>{_e(x)}</th>" for x in exercises]
    out.append("</tr>")
    for g in grades:
        out.append(f"<tr><td>{_e(g['student'])}</td><td>{g['score']:.2f} "
                   f"<span class=small>({g['passed']}/{g['scenarios']})</span></td>")
        for x in exercises:
            c = g["cells"].get(x)
            if c is None:
                out.append("<td>-</td>")
                continue
            out.append(f"<td>{_pf(c['passed'])} {c['score']:.2f}"
                       f"<div class=small>{_e(c.get('note', ''))}</div></td>")
        out.append("</tr>")
    out.append("</table>")
    return out


def render_html(rep: dict[str, Any]) -> str:
    parts = [f"<!doctype html><html><head><meta charset=utf-8><title>{_e(rep['title'])}"
             f"</title><style>{_CSS}</style></head><body><h1>{_e(rep['title'])}</h1>"]
    t = rep.get("timing", {})
    b = rep.get("backend", {})
    parts.append(f"<p class=small>{_e(rep['kind'])}; {t.get('runs', 0)} runs on "
                 f"{_e(b.get('kind', '?'))} ({b.get('workers', '?')} workers"
                 f"{', ' + _e(b['address']) if b.get('address') else ''}) in "
                 f"{t.get('wall_s', 0):.1f} s; {t.get('runs_per_minute') or 0:.1f} runs a minute;"
                 f" simulated {t.get('speed_vs_real_time') or 0:.1f}x real time a worker</p>")
    kind = rep["kind"]
    if kind == "suite":
        tot = rep["summary"]["totals"]
        parts.append(f"<p>Play: <b>{_e(rep.get('entrant', ''))}</b>; suite "
                     f"<b>{_e(rep.get('suite', ''))}</b>. Runs passed: {_pct(tot['pass_rate'])};"
                     f" scenarios passed: {tot['scenarios_passed']}/{tot['scenarios']}; mean "
                     f"score {tot['score'] if tot['score'] is not None else '-'}</p>")
        parts += _suite_html(rep["summary"], rep["runs"])
    elif kind == "ab-suite":
        ab = rep["ab"]
        parts.append(f"<h2>A/B</h2><p class=verdict>{_e(ab['difference']['verdict'])}</p>")
        parts.append(_bars([(f"A: {ab['a']}", ab["a_pass_rate"]["rate"] or 0.0,
                             ab["a_pass_rate"]["low"], ab["a_pass_rate"]["high"]),
                            (f"B: {ab['b']}", ab["b_pass_rate"]["rate"] or 0.0,
                             ab["b_pass_rate"]["low"], ab["b_pass_rate"]["high"])]))
        parts.append(f"<h2>A: {_e(ab['a'])}</h2>")
        parts += _suite_html(rep["a_summary"], rep["a_runs"])
        parts.append(f"<h2>B: {_e(ab['b'])}</h2>")
        parts += _suite_html(rep["b_summary"], rep["b_runs"])
    elif kind == "matches":
        parts += _matches_html(rep["summary"], rep["runs"])
    elif kind == "ab-matches":
        ab = rep["ab"]
        parts.append(f"<h2>A/B against {_e(ab['opponent'])}</h2><p class=verdict>"
                     f"{_e(ab['difference']['verdict'])}</p>")
        parts.append(_bars([(f"A: {ab['a']}", ab["a_win_rate"]["rate"] or 0.0,
                             ab["a_win_rate"]["low"], ab["a_win_rate"]["high"]),
                            (f"B: {ab['b']}", ab["b_win_rate"]["rate"] or 0.0,
                             ab["b_win_rate"]["low"], ab["b_win_rate"]["high"])]))
        parts += _matches_html(rep["a_summary"], rep["a_runs"])
        parts += _matches_html(rep["b_summary"], rep["b_runs"])
    elif kind == "class":
        parts += _class_html(rep)
        parts.append("<h2>Runs</h2>")
        parts += _suite_html(rep["summary"], rep["runs"])
    parts.append("</body></html>")
    return "".join(parts)
