import { useEffect, useMemo, useRef, useState } from "react";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { downloadText, toCsv } from "../plots/csv";
import {
  addPlot,
  addSignal,
  plotsStore,
  removePlot,
  removeSignal,
  samples,
  setWindow,
  togglePaused,
  usePlots,
  visibleRange,
  type PlotDef,
} from "../plots/sampler";
import { compareSignals, searchSignals } from "../plots/signals";

/** Readable on the dark background and distinct from each other (Okabe-Ito-like + extras). */
export const SERIES_COLORS = ["#60a5fa", "#fbbf24", "#34d399", "#f472b6", "#a78bfa", "#fb923c", "#22d3ee", "#e5e7eb"];

// ---- one animation-frame loop for every plot ----

interface LivePlot {
  id: number;
  keys: string[];
  u: uPlot;
  lastRows: number;
  lastT1: number;
  /** Latest x drawn (for tests). */
  lastX: number;
  points: number;
}

const live = new Map<number, LivePlot>();
let loopRaf = 0;
let frameNo = 0;
export const plotStats = { frames: 0, draws: 0 };
/** Redraw plots on every Nth animation frame (2 = 30 Hz at 60 Hz): keeps the field smooth. */
const PLOT_FRAME_DIVIDER = 2;
let plotsVisible = false;

function drawPlot(p: LivePlot, t0: number, t1: number): void {
  const w = samples.window(t0, t1, p.keys);
  p.u.batch(() => {
    p.u.setData([w.t, ...w.cols] as uPlot.AlignedData, false);
    p.u.setScale("x", { min: t0, max: t1 });
  });
  p.lastX = w.t.length ? (w.t[w.t.length - 1] as number) : Number.NaN;
  p.points = w.t.length;
  p.lastRows = samples.rows;
  p.lastT1 = t1;
  plotStats.draws++;
}

function loop(): void {
  loopRaf = live.size > 0 ? requestAnimationFrame(loop) : 0;
  plotStats.frames++;
  if (++frameNo % PLOT_FRAME_DIVIDER !== 0 || !plotsVisible) return;
  const [t0, t1] = visibleRange();
  const paused = plotsStore.getState().paused;
  for (const p of live.values()) {
    if (paused && p.lastT1 === t1) continue;
    // (abs: while replaying, the right edge jumps back on a seek)
    if (!paused && p.lastRows === samples.rows && Math.abs(t1 - p.lastT1) < 0.1) continue;
    drawPlot(p, t0, t1);
  }
}

function ensureLoop(): void {
  if (loopRaf === 0 && live.size > 0) loopRaf = requestAnimationFrame(loop);
}

/** For tests: what each plot shows. */
export function plotInfo(): { id: number; keys: string[]; lastX: number; points: number }[] {
  return [...live.values()].map((p) => ({ id: p.id, keys: p.keys, lastX: p.lastX, points: p.points }));
}

function exportCsv(defs: PlotDef[]): void {
  const keys = [...new Set(defs.flatMap((d) => d.keys))];
  if (keys.length === 0) return;
  const [t0, t1] = visibleRange();
  const w = samples.window(t0, t1, keys);
  const stamp = new Date().toISOString().replace(/[:.]/g, "-").slice(0, 19);
  downloadText(`touchline-plot-${stamp}.csv`, toCsv(w.t, keys, w.cols, { t0 }));
}

function unitOf(key: string): string {
  if (/_mps$/.test(key)) return "m/s";
  if (/_hz$/.test(key)) return "Hz";
  if (/_ms$/.test(key)) return "ms";
  if (/_s$/.test(key)) return "s";
  if (/\.(x|y|raw_x|raw_y)$/.test(key)) return "mm";
  if (/\.(vx|vy)$/.test(key)) return "mm/s";
  if (/orientation|radps|omega/.test(key)) return "rad";
  return "";
}

function PlotCard({ def, width }: { def: PlotDef; width: number }) {
  const hostRef = useRef<HTMLDivElement>(null);
  const [picking, setPicking] = useState(def.keys.length === 0);

  useEffect(() => {
    const host = hostRef.current;
    if (!host || def.keys.length === 0 || width <= 0) return;
    // One y scale per unit: the first unit on the left axis, the second on the right,
    // further units share the right axis's scale range only if they have the same unit.
    const units = def.keys.map((k) => unitOf(k) || "value");
    const scaleUnits = [...new Set(units)];
    const axisStyle = { stroke: "#94a3b8", grid: { stroke: "rgba(148,163,184,0.15)" }, ticks: { stroke: "rgba(148,163,184,0.3)" } };
    const yAxes: uPlot.Axis[] = scaleUnits.slice(0, 2).map((u, i) => ({
      ...axisStyle,
      scale: u,
      side: i === 0 ? 3 : 1,
      size: 56,
      label: u === "value" ? undefined : u,
      labelSize: 14,
      grid: i === 0 ? axisStyle.grid : { show: false },
    }));
    const opts: uPlot.Options = {
      width: Math.max(200, width),
      height: 150,
      pxAlign: false,
      cursor: { sync: { key: "touchline", setSeries: false }, drag: { x: false, y: false } },
      scales: { x: { time: true }, ...Object.fromEntries(scaleUnits.map((u) => [u, { auto: true }])) },
      legend: { show: true, live: true },
      axes: [axisStyle, ...yAxes],
      series: [
        { label: "time" },
        ...def.keys.map((k, i) => ({
          label: k,
          scale: units[i],
          stroke: SERIES_COLORS[i % SERIES_COLORS.length] as string,
          width: 1.5,
          spanGaps: true,
          points: { show: false },
        })),
      ],
    };
    const [t0, t1] = visibleRange();
    const w = samples.window(t0, t1, def.keys);
    const u = new uPlot(opts, [w.t, ...w.cols] as uPlot.AlignedData, host);
    const lp: LivePlot = { id: def.id, keys: def.keys, u, lastRows: -1, lastT1: 0, lastX: Number.NaN, points: 0 };
    live.set(def.id, lp);
    drawPlot(lp, t0, t1);
    ensureLoop();
    return () => {
      live.delete(def.id);
      u.destroy();
    };
  }, [def.id, def.keys, width]);

  return (
    <div className="plot-card" data-testid={`plot-${def.id}`} data-keys={def.keys.join(" ")}>
      <div className="plot-head">
        <div className="plot-chips">
          {def.keys.map((k, i) => (
            <span key={k} className="sig-chip" style={{ borderColor: SERIES_COLORS[i % SERIES_COLORS.length] }}>
              {k}
              <button type="button" aria-label={`Remove ${k}`} onClick={() => removeSignal(def.id, k)}>
                ×
              </button>
            </span>
          ))}
          {def.keys.length === 0 && <span className="muted">empty plot: add a signal</span>}
        </div>
        <button type="button" className="btn btn-small" data-testid="plot-add-signal" onClick={() => setPicking((v) => !v)}>
          + signal
        </button>
        <button type="button" className="btn btn-small" title="Export this plot's visible data as CSV" onClick={() => exportCsv([def])}>
          CSV
        </button>
        <button type="button" className="btn btn-small" aria-label="Remove plot" onClick={() => removePlot(def.id)}>
          ✕
        </button>
      </div>
      {picking && <SignalPicker
          onPick={(k) => {
            addSignal(def.id, k);
            setPicking(false);
          }}
          onClose={() => setPicking(false)} />}
      <div ref={hostRef} className="plot-host" data-testid="plot-canvas-host" />
    </div>
  );
}

function SignalPicker({ onPick, onClose }: { onPick: (key: string) => void; onClose: () => void }) {
  const [q, setQ] = useState("");
  const [keys, setKeys] = useState<string[]>(() => samples.keys().sort(compareSignals));
  useEffect(() => {
    const t = setInterval(() => setKeys(samples.keys().sort(compareSignals)), 1000);
    return () => clearInterval(t);
  }, []);
  const matches = useMemo(() => searchSignals(keys, q, 150), [keys, q]);
  return (
    <div className="picker" data-testid="signal-picker">
      <input
        className="text grow"
        type="search"
        autoFocus
        placeholder={`Search ${keys.length} signals: e.g. "blue 3 speed", "vision rate"`}
        value={q}
        data-testid="signal-search"
        onChange={(ev) => setQ(ev.target.value)}
        onKeyDown={(ev) => {
          ev.stopPropagation();
          if (ev.key === "Enter" && matches[0]) onPick(matches[0]);
          if (ev.key === "Escape") onClose();
        }}
      />
      <ul className="picker-list" role="listbox">
        {matches.map((k) => (
          <li key={k}>
            <button type="button" role="option" aria-selected={false} data-testid={`signal-${k}`} onClick={() => onPick(k)}>
              {k}
            </button>
          </li>
        ))}
        {matches.length === 0 && <li className="muted">no signal matches</li>}
      </ul>
    </div>
  );
}

export function PlotsPanel({ visible }: { visible: boolean }) {
  const state = usePlots();
  const bodyRef = useRef<HTMLDivElement>(null);
  const [width, setWidth] = useState(0);
  useEffect(() => {
    plotsVisible = visible;
  }, [visible]);
  useEffect(() => {
    const el = bodyRef.current;
    if (!el) return;
    const ro = new ResizeObserver(() => {
      const w = Math.floor(el.getBoundingClientRect().width);
      if (w > 0) setWidth(w - 20); // body padding + card border
    });
    ro.observe(el);
    return () => ro.disconnect();
  }, []);
  return (
    <div className="plots" data-testid="plots-panel">
      <div className="row plots-toolbar">
        <button type="button" className="btn btn-small" data-testid="add-plot" onClick={() => addPlot()}>
          + Plot
        </button>
        <label className="muted">
          window{" "}
          <select value={state.windowS} data-testid="plot-window" onChange={(ev) => setWindow(Number(ev.target.value))}>
            {[5, 10, 20, 30, 60].map((s) => (
              <option key={s} value={s}>
                {s} s
              </option>
            ))}
          </select>
        </label>
        <button type="button" className={`btn btn-small ${state.paused ? "btn-warn" : ""}`} data-testid="plots-pause" onClick={togglePaused} title="Space">
          {state.paused ? "▶ Resume" : "❚❚ Pause"}
        </button>
        <button type="button" className="btn btn-small" onClick={() => exportCsv(state.plots)} data-testid="plots-csv">
          CSV (all)
        </button>
      </div>
      <div ref={bodyRef} className="plots-body">
        {state.plots.length === 0 && <p className="muted">No plots. “+ Plot”, then pick signals (world, robots, ball, health).</p>}
        {visible || live.size > 0
          ? state.plots.map((p) => <PlotCard key={p.id} def={p} width={width} />)
          : null}
      </div>
    </div>
  );
}
