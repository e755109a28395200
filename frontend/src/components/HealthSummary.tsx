import { useAppState } from "../store/hooks";
import { fmtFixed } from "../format";
import { refereeSilentFor } from "../referee";
import { engineOf, engineSummary } from "../strategy/engine";

/** Compact station health, shown in the details panel while no robot is selected. */
export function HealthSummary() {
  const health = useAppState((s) => s.health);
  if (!health) return <p className="muted">No health data yet.</p>;
  const silentFor = refereeSilentFor(health);
  const order = (name: string) => (name === "vision" ? 0 : name === "referee" ? 1 : 2);
  const streams = Object.entries(health.streams)
    .sort(([a], [b]) => order(a) - order(b) || a.localeCompare(b))
    .slice(0, 5);
  const engine = engineOf(health);
  const eng = engineSummary(engine);
  return (
    <dl className="details-grid health" data-testid="health-summary">
      {streams.map(([name, s]) => {
        const silent = name === "referee" ? silentFor : null;
        return (
          <div className="health-row" key={name} title={s.last_error || undefined}>
            <dt title={name}>{name}</dt>
            <dd
              className={`num ${s.errors > 0 || (name === "vision" && s.rate_hz <= 0) || silent !== null ? "warn" : ""}`}
              data-testid={`health-summary-stream-${name}`}
            >
              {fmtFixed(s.rate_hz, 1)} Hz{s.errors > 0 ? ` · ${s.errors} err` : ""}
              {silent !== null ? ` · silent ${silent} s` : ""}
            </dd>
          </div>
        );
      })}
      {health.relay && (
        <div className="health-row">
          <dt>relay</dt>
          <dd className={`num ${health.relay.alive ? "" : "warn"}`}>
            {health.relay.alive ? `${health.relay.output_mode} ${fmtFixed(health.relay.output_rate_hz, 0)} Hz` : "down"}
          </dd>
        </div>
      )}
      <div className="health-row" title={engine?.last_error || undefined}>
        <dt>engine</dt>
        <dd className={`num ${eng.warn ? "warn" : ""}`} data-testid="health-summary-engine">
          {eng.text}
        </dd>
      </div>
    </dl>
  );
}
