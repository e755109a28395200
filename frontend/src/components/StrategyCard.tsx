import { fmtFixed } from "../format";
import { useAppState } from "../store/hooks";
import { situationLine } from "../strategy/plays";
import { PlaySelector } from "./PlaySelector";

/** The Robots tab's strategy block: the play (with its description) and the situation. */
export function StrategyCard() {
  const situation = useAppState((s) => s.world?.strategy?.situation ?? null);
  const text = useAppState((s) => s.world?.strategy?.situation_text ?? null);
  const side = useAppState((s) => s.world?.strategy?.our_side ?? null);
  const fromRef = useAppState((s) => s.world?.strategy?.side_from_referee ?? false);
  const team = useAppState((s) => s.world?.strategy?.our_team ?? null);
  // Rounded so the card does not re-render for every tick time.
  const tick = useAppState((s) => {
    const v = s.world?.strategy?.tick_ms;
    return typeof v === "number" && Number.isFinite(v) ? Math.round(v * 10) / 10 : null;
  });
  const line = situationLine({
    situation: situation ?? "",
    situation_text: text ?? "",
    ...(side ? { our_side: side } : {}),
    side_from_referee: fromRef,
  });
  return (
    <section className="strategy-card" aria-label="Strategy" data-testid="strategy-card">
      <PlaySelector variant="panel" />
      {line && (
        <p className="strategy-situation" data-testid="strategy-situation">
          {team && <span className={`chip chip-${team}`} aria-hidden="true" />}
          <b>{line.text || "—"}</b>
          {line.side && <span className="muted-inline"> · {line.side}</span>}
          {tick !== null && <span className="muted-inline num"> · tick {fmtFixed(tick, 1)} ms</span>}
        </p>
      )}
    </section>
  );
}
