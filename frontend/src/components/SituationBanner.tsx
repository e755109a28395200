import { useAppState } from "../store/hooks";
import { situationLine } from "../strategy/plays";

/**
 * What the strategy makes of the game ("STOP: keep 0.5 m from the ball", "Our kickoff: take
 * positions") and the goal we defend, over the bottom-left corner of the field. Clicks pass
 * through to the field. Nothing while the station reports no strategy.
 */
export function SituationBanner() {
  // Primitive slices: re-rendered when the text changes, not on every world message.
  const text = useAppState((s) => s.world?.strategy?.situation_text ?? null);
  const situation = useAppState((s) => s.world?.strategy?.situation ?? null);
  const side = useAppState((s) => s.world?.strategy?.our_side ?? null);
  const fromRef = useAppState((s) => s.world?.strategy?.side_from_referee ?? false);
  const team = useAppState((s) => s.world?.strategy?.our_team ?? null);
  if (situation === null && text === null) return null;
  const line = situationLine({
    situation: situation ?? "",
    situation_text: text ?? "",
    ...(side ? { our_side: side } : {}),
    side_from_referee: fromRef,
  });
  if (!line) return null;
  return (
    <div className="situation" data-testid="situation-banner" data-situation={situation ?? ""} aria-live="polite">
      {team && <span className={`chip chip-${team}`} aria-hidden="true" />}
      <span className="situation-text" data-testid="situation-text">
        {line.text}
      </span>
      {line.side && (
        <span className="situation-side" data-testid="situation-side">
          {line.side}
        </span>
      )}
    </div>
  );
}
