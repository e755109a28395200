// The replay timeline under the field (only while a log is open): play/pause, speed, a seek
// bar with the log's events, frame steps and event jumps.

import { useRef, useState, useSyncExternalStore, type PointerEvent as ReactPointerEvent, type ReactNode } from "react";
import type { Player } from "../api/types";
import {
  backToLive,
  changeSpeed,
  jump,
  seek,
  shownSpeed,
  speedStore,
  step,
  togglePlay,
} from "../player/actions";
import {
  findEvent,
  fmtDuration,
  fmtPosition,
  fmtWallTime,
  layoutMarkers,
  prettyStage,
  SPEEDS,
  speedLabel,
  xToPosition,
} from "../player/timeline";
import { useAppState, useThrottledWorld } from "../store/hooks";
import { fmtClock } from "./RefereePanel";

/** A step or jump button of the controls (an icon, its name for screen readers). */
function StepButton({ label, title, testId, onClick, children }: {
  label: string;
  title: string;
  testId: string;
  onClick: () => void;
  children: ReactNode;
}) {
  return (
    <button type="button" className="btn btn-small btn-icon" aria-label={label} title={title} data-testid={testId} onClick={onClick}>
      {children}
    </button>
  );
}

/** While dragging, a seek goes out at most this often (the last one on release). */
const DRAG_SEEK_MS = 300;

function usePendingSpeed(): number | null {
  return useSyncExternalStore(
    speedStore.subscribe,
    () => speedStore.getState().pending,
    () => speedStore.getState().pending,
  );
}

/** Previous / next event: a bar and two triangles, drawn (the ⏮ ⏭ glyphs are missing from
 * many fonts). */
function EventIcon({ direction }: { direction: "prev" | "next" }) {
  const d = "M2 2h2v12H2zM14 2v12L9 8zM9 2v12L4 8z";
  return (
    <svg className="tl-icon" viewBox="0 0 16 16" width="14" height="14" aria-hidden="true" focusable="false">
      <path d={d} fill="currentColor" transform={direction === "next" ? "matrix(-1 0 0 1 16 0)" : undefined} />
    </svg>
  );
}

function TimelineBody({ player }: { player: Player }) {
  const world = useThrottledWorld(100);
  const pending = usePendingSpeed();
  const barRef = useRef<HTMLDivElement>(null);
  const [drag, setDrag] = useState<number | null>(null);
  const [hover, setHover] = useState<number | null>(null);
  const lastSeekAt = useRef(0);

  // The world's replay clock moves with every frame; after an open or a seek the player's
  // answer (a new epoch) may come before the first world of that epoch: trust the newer one.
  const clock = world?.replay ?? null;
  const replay = clock && clock.epoch === player.epoch ? clock : null;
  const duration = replay?.duration_s ?? player.duration_s;
  const livePosition = replay ? replay.position_s : player.position_s;
  const position = drag ?? livePosition;
  const tUnix = drag !== null ? player.start_unix + drag : (replay?.t_unix ?? player.start_unix + player.position_s);
  const pct = duration > 0 ? Math.max(0, Math.min(100, (position / duration) * 100)) : 0;
  const speed = shownSpeed(player, pending);
  const markers = layoutMarkers(player.events, duration);
  const ref = world?.referee ?? null;
  const prevEvent = findEvent(player.events, position, "prev");
  const nextEvent = findEvent(player.events, position, "next");
  const eventTitle = (what: string, e: typeof prevEvent) =>
    e ? `${what}: ${e.label} (${e.kind}) at ${fmtPosition(e.t_s)}` : `${what}: none`;

  const posAt = (clientX: number): number => {
    const el = barRef.current;
    if (!el) return 0;
    const r = el.getBoundingClientRect();
    return xToPosition(clientX - r.left, duration, r.width);
  };

  const onDown = (ev: ReactPointerEvent<HTMLDivElement>) => {
    if (ev.button !== 0 || duration <= 0) return;
    try {
      ev.currentTarget.setPointerCapture?.(ev.pointerId);
    } catch {
      /* no capture (synthetic events): the drag still ends on pointerup over the bar */
    }
    setDrag(posAt(ev.clientX));
    lastSeekAt.current = performance.now();
  };
  const onMove = (ev: ReactPointerEvent<HTMLDivElement>) => {
    const p = posAt(ev.clientX);
    setHover(p);
    if (drag === null) return;
    setDrag(p);
    const now = performance.now();
    if (now - lastSeekAt.current >= DRAG_SEEK_MS) {
      lastSeekAt.current = now;
      void seek(p);
    }
  };
  const onUp = (ev: ReactPointerEvent<HTMLDivElement>) => {
    if (drag === null) return;
    const p = posAt(ev.clientX);
    setDrag(null);
    void seek(p);
  };

  const shownTip = drag ?? hover;
  const tipPct = shownTip !== null && duration > 0 ? (shownTip / duration) * 100 : 0;

  return (
    <div className="timeline" data-testid="timeline" data-playing={player.playing ? "true" : "false"}>
      <div className="tl-controls">
        <StepButton label="Previous event" title={eventTitle("Previous event", prevEvent)} testId="timeline-prev-event" onClick={() => void jump("prev")}>
          <EventIcon direction="prev" />
        </StepButton>
        <StepButton label="One frame back" title="One camera frame back (←)" testId="timeline-step-back" onClick={() => void step(-1)}>
          ◀︎|
        </StepButton>
        <button
          type="button"
          className={`btn btn-small tl-play ${player.playing ? "" : "btn-on"}`}
          aria-label={player.playing ? "Pause" : "Play"}
          title={`${player.playing ? "Pause" : "Play"} (Space)`}
          data-testid="timeline-play"
          data-state={player.playing ? "playing" : "paused"}
          onClick={() => void togglePlay()}
        >
          {player.playing ? "❚❚" : "▶"}
        </button>
        <StepButton label="One frame forward" title="One camera frame forward (→)" testId="timeline-step-forward" onClick={() => void step(1)}>
          |▶︎
        </StepButton>
        <StepButton label="Next event" title={eventTitle("Next event", nextEvent)} testId="timeline-next-event" onClick={() => void jump("next")}>
          <EventIcon direction="next" />
        </StepButton>
        <select
          className="tl-speed"
          aria-label="Replay speed"
          title="Replay speed (+ / −)"
          data-testid="timeline-speed"
          value={String(speed)}
          onChange={(ev) => void changeSpeed(Number(ev.target.value))}
        >
          {!SPEEDS.includes(speed) && <option value={String(speed)}>{speedLabel(speed)}</option>}
          {SPEEDS.map((s) => (
            <option key={s} value={String(s)}>
              {speedLabel(s)}
            </option>
          ))}
        </select>
      </div>
      <div
        ref={barRef}
        className={`tl-bar ${drag !== null ? "is-dragging" : ""}`}
        data-testid="timeline-bar"
        role="slider"
        tabIndex={0}
        aria-label="Replay position"
        aria-valuemin={0}
        aria-valuemax={Math.round(duration * 10) / 10}
        aria-valuenow={Math.round(position * 10) / 10}
        aria-valuetext={`${fmtPosition(position)} of ${fmtDuration(duration)}`}
        onPointerDown={onDown}
        onPointerMove={onMove}
        onPointerUp={onUp}
        onPointerCancel={() => setDrag(null)}
        onPointerLeave={() => setHover(null)}
      >
        <div className="tl-track" />
        <div className="tl-fill" style={{ width: `${pct}%` }} />
        {markers.map(({ event, pct: mp, row }, i) => (
          <span
            key={`${event.t_s}-${i}`}
            className={`tl-marker tl-kind-${event.kind}`}
            style={{ left: `${mp}%`, top: `${row * 5}px` }}
            title={`${fmtPosition(event.t_s)} ${event.kind}: ${event.label}`}
            aria-label={`${event.kind} ${event.label}`}
            data-testid="timeline-marker"
            data-kind={event.kind}
            data-t={event.t_s}
          />
        ))}
        <div className="tl-head" style={{ left: `${pct}%` }} />
        {shownTip !== null && (
          <div className="tl-tip num" style={{ left: `${tipPct}%` }} data-testid="timeline-tip">
            {fmtPosition(shownTip)}
          </div>
        )}
      </div>
      <div className="tl-info num">
        <span className="tl-pos" data-testid="timeline-position">
          {fmtPosition(position)} / {fmtDuration(duration)}
        </span>
        {fmtWallTime(tUnix) && (
          <span className="tl-wall" title="The log's wall time at the playhead (local)" data-testid="timeline-wall">
            {fmtWallTime(tUnix)}
          </span>
        )}
        {ref && ref.stage && (
          <span className="tl-stage" data-testid="timeline-stage" title="Stage and time left in it">
            {prettyStage(ref.stage)}
            {ref.stage_time_left_s !== null ? ` ${fmtClock(ref.stage_time_left_s)}` : ""}
          </span>
        )}
        {player.error && (
          <span className="tl-error" data-testid="timeline-error" title={player.error}>
            {player.error}
          </span>
        )}
        {player.warning && (
          <span className="tl-warning" data-testid="timeline-warning" title={player.warning}>
            ⚠ {player.warning}
          </span>
        )}
        {player.loading !== null && (
          <span className="tl-loading" data-testid="timeline-loading">
            indexing {Math.round(player.loading * 100)}%
          </span>
        )}
      </div>
      <button
        type="button"
        className="btn btn-small tl-live"
        data-testid="timeline-live"
        title="Close the log and go back to the live station"
        onClick={() => void backToLive()}
      >
        ● Live
      </button>
    </div>
  );
}

export function Timeline() {
  const player = useAppState((s) => s.player);
  if (!player || player.source !== "log") return null;
  return <TimelineBody player={player} />;
}
