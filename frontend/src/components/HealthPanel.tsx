import { FRAME_AGE_STAGE } from "../api/contract.gen";
import type { Health } from "../api/types";
import { fmtFixed } from "../format";
import { useAppState } from "../store/hooks";
import { engineOf, engineRows } from "../strategy/engine";
import { OperatorsHealth } from "./OperatorsPanel";

/** A horizontal bar: value/max filled, an optional marker (e.g. the configured rate). */
function Bar({ value, max, marker, warn, label }: { value: number; max: number; marker?: number | null; warn?: boolean; label?: string }) {
  const frac = max > 0 && Number.isFinite(value) ? Math.max(0, Math.min(1, value / max)) : 0;
  const m = marker !== undefined && marker !== null && max > 0 ? Math.max(0, Math.min(1, marker / max)) : null;
  return (
    <div className="hbar" role="meter" aria-valuenow={value} aria-valuemax={max} aria-label={label}>
      <div className={`hbar-fill ${warn ? "hbar-warn" : ""}`} style={{ width: `${frac * 100}%` }} />
      {m !== null && <div className="hbar-mark" style={{ left: `${m * 100}%` }} title={`configured ${marker}`} />}
    </div>
  );
}

function niceMax(v: number): number {
  if (!(v > 0)) return 1;
  const p = 10 ** Math.floor(Math.log10(v));
  for (const k of [1, 2, 2.5, 5, 10]) if (k * p >= v) return k * p;
  return 10 * p;
}

function Processors({ h }: { h: Health }) {
  const rateMax = niceMax(Math.max(...h.processors.map((p) => Math.max(p.measured_hz, p.configured_hz ?? 0)), 1));
  const tickMax = niceMax(Math.max(...h.processors.map((p) => p.tick_p99_ms), 0.1));
  return (
    <section>
      <h3>
        Processors <span className="muted">rate (bar, | = configured) · tick mean / p99 (scale {tickMax} ms)</span>
      </h3>
      <table className="htable" data-testid="health-processors">
        <tbody>
          {h.processors.map((p) => {
            const slow = p.configured_hz !== null && p.configured_hz > 0 && p.measured_hz < 0.8 * p.configured_hz;
            return (
              <tr key={p.name} title={`${p.trigger}${p.last_error ? ` · last error: ${p.last_error}` : ""}`}>
                <td className="hname">{p.name}</td>
                <td className="hbarcell">
                  <Bar value={p.measured_hz} max={rateMax} marker={p.configured_hz} warn={slow} label={`${p.name} rate`} />
                </td>
                <td className="num hval">
                  {fmtFixed(p.measured_hz, 0)}
                  {p.configured_hz ? `/${fmtFixed(p.configured_hz, 0)}` : ""} Hz
                </td>
                <td className="hbarcell">
                  <div className="hbar-stack">
                    <Bar value={p.tick_mean_ms} max={tickMax} label={`${p.name} tick mean`} />
                    <Bar value={p.tick_p99_ms} max={tickMax} warn={p.tick_p99_ms > 5} label={`${p.name} tick p99`} />
                  </div>
                </td>
                <td className="num hval">
                  {fmtFixed(p.tick_mean_ms, 2)}/{fmtFixed(p.tick_p99_ms, 2)} ms
                </td>
                <td className={`num hval ${p.overruns || p.errors ? "warn" : ""}`}>
                  {p.overruns ? `${p.overruns} ovr` : ""}
                  {p.errors ? ` ${p.errors} err` : ""}
                  {!p.overruns && !p.errors ? "ok" : ""}
                </td>
              </tr>
            );
          })}
        </tbody>
      </table>
    </section>
  );
}

/** How often the launcher restarted a process (0 when not started by the launcher). */
function restarts(h: Health, name: string): number {
  return h.supervisor?.find((c) => c.name === name)?.restarts ?? 0;
}

/** CPU (% of one core) and memory of each station process, drawn against one core, with
 * the launcher's restarts. */
export function Processes({ h }: { h: Health }) {
  const procs = h.processes ?? [];
  if (procs.length === 0) return null;
  const total = procs.reduce((a, p) => a + p.cpu_percent, 0);
  return (
    <section>
      <h3>
        Processes <span className="muted">CPU, % of one core · together {fmtFixed(total, 0)} %</span>
      </h3>
      <table className="htable" data-testid="health-processes">
        <tbody>
          {procs.map((p) => (
            <tr key={p.name} data-testid={`health-process-${p.name}`}>
              <td className="hname">{p.name}</td>
              <td className="hbarcell">
                <Bar value={p.cpu_percent} max={100} warn={p.cpu_percent > 50} label={`${p.name} CPU`} />
              </td>
              <td className="num hval">{fmtFixed(p.cpu_percent, 1)} %</td>
              <td className="num hval">{fmtFixed(p.rss_mb, 0)} MB</td>
              <td className={`num hval ${restarts(h, p.name) ? "warn" : ""}`} data-testid={`health-restarts-${p.name}`}>
                {restarts(h, p.name) ? `${restarts(h, p.name)} restarts` : ""}
              </td>
            </tr>
          ))}
        </tbody>
      </table>
    </section>
  );
}

/** A calibration offset worth a look: two cameras this far apart on the same robots. */
export const CAMERA_PAIR_WARN_MM = 20;

/** When every camera is silent: each camera's rate, the silence after which every robot is
 * stopped (the vision_stale_s rule when a camera is slow or not measured yet), and the stop. */
function CameraRates({ w }: { w: NonNullable<Health["world"]> }) {
  const rates = Object.entries(w.camera_rates_hz);
  if (rates.length === 0) return null;
  const after = w.lost_after_s === null ? "safety.vision_stale_s" : `${fmtFixed(w.lost_after_s * 1000, 0)} ms`;
  return (
    <p className={w.vision_lost ? "warn" : "muted"} data-testid="health-camera-rates">
      {rates.map(([c, r]) => `cam ${c}: ${r > 0 ? `${fmtFixed(r, 0)} Hz` : "—"}`).join(" · ")}
      {` · all silent: robots stopped after ${after}`}
      {w.vision_lost ? ` · ${w.vision_lost}` : ""}
    </p>
  );
}

/** Camera agreement: per pair of cameras, how far apart they see the robots both see (a
 * calibration offset), and each camera's clock offset; each camera's rate. */
export function Cameras({ h }: { h: Health }) {
  const w = h.world;
  if (
    !w ||
    (w.camera_pairs.length === 0 && Object.keys(w.camera_clock_offsets_s).length === 0 && Object.keys(w.camera_rates_hz).length === 0)
  )
    return null;
  return (
    <section>
      <h3>
        Cameras <span className="muted">b − a on the robots both see (still ones), mm · clock offsets, s</span>
      </h3>
      {w.camera_pairs.length > 0 && (
        <table className="htable" data-testid="health-camera-pairs">
          <tbody>
            {w.camera_pairs.map((p) => {
              const off = Math.hypot(p.dx_mm, p.dy_mm);
              return (
                <tr key={`${p.camera_a}-${p.camera_b}`} data-testid={`health-camera-pair-${p.camera_a}-${p.camera_b}`}>
                  <td className="hname">
                    cam {p.camera_a} ↔ {p.camera_b}
                  </td>
                  <td className={`num hval ${off > CAMERA_PAIR_WARN_MM ? "warn" : ""}`}>
                    {fmtFixed(p.dx_mm, 1)}, {fmtFixed(p.dy_mm, 1)} mm
                  </td>
                  <td className="num hval muted">{p.samples}</td>
                </tr>
              );
            })}
          </tbody>
        </table>
      )}
      <p className="muted" data-testid="health-camera-clocks">
        {Object.entries(w.camera_clock_offsets_s)
          .map(([c, o]) => `cam ${c}: ${o === null ? "—" : fmtFixed(o, 3)}`)
          .join(" · ")}
      </p>
      <CameraRates w={w} />
    </section>
  );
}

function Topics({ h }: { h: Health }) {
  return (
    <section>
      <h3>
        Data Bus topics <span className="muted">fill (size / capacity) · age of the newest record</span>
      </h3>
      <table className="htable" data-testid="health-topics">
        <tbody>
          {h.topics.map((t) => (
            <tr key={t.name}>
              <td className="hname">{t.name}</td>
              <td className="hbarcell">
                <Bar value={t.size} max={t.capacity} label={`${t.name} fill`} />
              </td>
              <td className="num hval">
                {t.size}/{t.capacity}
              </td>
              <td className="num hval">{t.age_s < 0 ? "never" : t.age_s < 1 ? `${fmtFixed(t.age_s * 1000, 0)} ms` : `${fmtFixed(t.age_s, 1)} s`}</td>
            </tr>
          ))}
        </tbody>
      </table>
    </section>
  );
}

function Streams({ h }: { h: Health }) {
  const entries = Object.entries(h.streams);
  const max = niceMax(Math.max(...entries.map(([, s]) => s.rate_hz), 1));
  return (
    <section>
      <h3>
        Streams <span className="muted">packets per second (scale {max} Hz) · errors</span>
      </h3>
      <table className="htable" data-testid="health-streams">
        <tbody>
          {entries.map(([name, s]) => (
            <tr key={name} title={s.last_error || undefined}>
              <td className="hname">{name}</td>
              <td className="hbarcell">
                <Bar value={s.rate_hz} max={max} warn={s.errors > 0} label={`${name} rate`} />
              </td>
              <td className="num hval">{fmtFixed(s.rate_hz, 0)} Hz</td>
              <td className={`num hval ${s.errors ? "warn" : ""}`}>{s.errors ? `${s.errors} err` : s.packets ? "ok" : "idle"}</td>
            </tr>
          ))}
        </tbody>
      </table>
      <ErrorsByReason h={h} />
    </section>
  );
}

/** Every refused datagram counted by reason, per stream (the last error as a tooltip). */
export function ErrorsByReason({ h }: { h: Health }) {
  const rows = Object.entries(h.streams).flatMap(([name, s]) =>
    Object.entries(s.errors_by_reason ?? {})
      .filter(([, n]) => n > 0)
      .map(([reason, n]) => ({ name, reason, n, last: s.last_error })),
  );
  if (rows.length === 0) return null;
  return (
    <table className="htable" data-testid="health-errors">
      <thead>
        <tr>
          <th className="hname">refused</th>
          <th>reason</th>
          <th className="num">count</th>
        </tr>
      </thead>
      <tbody>
        {rows.map((r) => (
          <tr key={`${r.name}/${r.reason}`} title={r.last || undefined} data-testid={`health-error-${r.name}-${r.reason.replace(/ /g, "-")}`}>
            <td className="hname">{r.name}</td>
            <td>{r.reason}</td>
            <td className="num hval warn">{r.n}</td>
          </tr>
        ))}
      </tbody>
    </table>
  );
}

export function Latency({ h }: { h: Health }) {
  const lat = h.latency;
  const relay = h.relay;
  // what the robot sees: its newest frame's age when its command leaves for the relay
  const age = h.latency_stages.find((s) => s.stage === FRAME_AGE_STAGE);
  const rows: [string, number | null | undefined][] = [
    ["vision → command p50", lat?.p50_ms],
    ["vision → command mean", lat?.mean_ms],
    ["vision → command p99", lat?.p99_ms],
    ["→ robot datagram p50", relay?.command_latency_p50_ms],
    ["→ robot datagram p99", relay?.command_latency_p99_ms],
    ["robot's newest frame p50", age?.p50_ms],
    ["robot's newest frame p99", age?.p99_ms],
  ];
  const max = niceMax(Math.max(...rows.map(([, v]) => v ?? 0), 1));
  return (
    <section>
      <h3>
        Latency <span className="muted">vision arrival at the relay → commands sent to the relay (backend), → the command datagram sent (relay); the age of each commanded robot's newest frame when its command is sent (what the robot sees) · scale {max} ms</span>
      </h3>
      <table className="htable" data-testid="health-latency">
        <tbody>
          {rows.map(([name, v]) => (
            <tr key={name}>
              <td className="hname">{name}</td>
              <td className="hbarcell">
                <Bar value={v ?? 0} max={max} warn={(v ?? 0) > 20} label={name} />
              </td>
              <td className="num hval">{v === undefined || v === null ? "—" : `${fmtFixed(v, 2)} ms`}</td>
            </tr>
          ))}
        </tbody>
      </table>
      {relay && (
        <p className="muted">
          relay {relay.alive ? "alive" : "DOWN"} · output {relay.output_mode} {fmtFixed(relay.output_rate_hz, 0)} Hz · {relay.active_robots} active,{" "}
          {relay.stale_robots} stale robots · {h.websocket_clients} browser{h.websocket_clients === 1 ? "" : "s"}
        </p>
      )}
    </section>
  );
}

/** The compute engine the strategy calls: kind, function, rate, latency, failures, workers, fallbacks. */
export function EnginePanel({ h }: { h: Health }) {
  const e = engineOf(h);
  return (
    <section className="engine-panel" data-testid="engine-panel" data-engine={e ? String(e.kind) : "off"}>
      <h3>
        Engine <span className="muted">compute engine of the strategy (paper: MATLAB Engine)</span>
      </h3>
      {!e ? (
        <p className="muted" data-testid="engine-off">
          engine off: the strategy runs its built-in numpy code
        </p>
      ) : (
        <>
          <dl className="details-grid engine-grid" data-testid="engine-details">
            {engineRows(e).map((r) => (
              <div className="health-row" key={r.key}>
                <dt>{r.label}</dt>
                <dd className={`num ${r.warn ? "warn" : ""}`} data-testid={`engine-${r.key}`}>
                  {r.value}
                </dd>
              </div>
            ))}
          </dl>
          {e.last_error && (
            <div className="engine-error" role="alert" data-testid="engine-last-error">
              <b>last error</b> {e.last_error}
            </div>
          )}
        </>
      )}
    </section>
  );
}

/** The latched emergency stop as the station and the relay report it. */
export function EstopHealth({ h }: { h: Health }) {
  const e = h.estop;
  const since = e.since > 0 ? new Date(e.since * 1000).toLocaleTimeString() : "";
  const relay = e.relay_latched === null ? "relay latch unknown" : e.relay_latched ? "latched in the relay" : "not latched in the relay";
  return (
    <p className={e.active ? "notice" : "muted"} data-testid="health-estop" data-active={e.active ? "true" : "false"} data-relay-latched={String(e.relay_latched)}>
      {e.active ? "Emergency stop ACTIVE" : "Emergency stop released"}
      {since ? ` since ${since}` : ""}
      {e.by ? ` (${e.by})` : ""} · {relay}
    </p>
  );
}

/** Arming (real robots): armed or not, by whom, and what the relay says; nothing where it is
 * not required (the built-in simulator). */
export function ArmingHealth({ h }: { h: Health }) {
  const a = h.arming;
  if (!a || !a.required) return null;
  const since = a.since > 0 ? new Date(a.since * 1000).toLocaleTimeString() : "";
  const relay = a.relay_armed === null ? "relay arming unknown" : a.relay_armed ? "relay armed" : "relay disarmed";
  return (
    <p className={a.armed ? "notice" : "muted"} data-testid="health-arming" data-armed={a.armed ? "true" : "false"}>
      {a.armed ? "ARMED: commands reach the robots" : "Disarmed: only stops reach the robots"}
      {since ? ` since ${since}` : ""}
      {a.by ? ` (${a.by})` : ""} · {relay}
      {!a.armed && a.refusal ? ` · arming refused now: ${a.refusal}` : ""}
    </p>
  );
}

/** Who may do what on this station (docs/security.md) and the refusals so far. */
export function AccessHealth({ h }: { h: Health }) {
  const a = h.access;
  if (!a) return null;
  const rule = a.token_required
    ? `changes need the operator token${a.view_token ? ", viewing a token too" : ""}${a.estop_for_all ? ", every viewer may press the e-stop" : ""}`
    : "no token needed (loopback)";
  const refused = Object.entries(a.refused).filter(([, n]) => n > 0);
  return (
    <p className={a.blocked_clients > 0 ? "notice" : "muted"} data-testid="health-access">
      Access: {rule}
      {refused.length > 0 ? ` · refused: ${refused.map(([why, n]) => `${why} ${n}`).join(", ")}` : ""}
      {a.blocked_clients > 0 ? ` · ${a.blocked_clients} address${a.blocked_clients === 1 ? "" : "es"} blocked for wrong tokens` : ""}
    </p>
  );
}

export function HealthPanel() {
  const h = useAppState((s) => s.health);
  if (!h) return <p className="muted">No health data yet.</p>;
  return (
    <div className="health-panel" data-testid="health-panel">
      <p className={h.ok ? "ok-line" : "notice"}>{h.ok ? "Station healthy" : "Station reports a problem"}</p>
      <EstopHealth h={h} />
      <ArmingHealth h={h} />
      <AccessHealth h={h} />
      <OperatorsHealth h={h} />
      {(h.warnings ?? []).length > 0 && (
        <ul className="health-warnings" data-testid="health-warnings">
          {(h.warnings ?? []).map((w, i) => (
            <li key={i}>{w}</li>
          ))}
        </ul>
      )}
      <Latency h={h} />
      <Processes h={h} />
      <EnginePanel h={h} />
      <Processors h={h} />
      <Streams h={h} />
      <Cameras h={h} />
      <Topics h={h} />
    </div>
  );
}
