import { useEffect } from "react";
import { useParamForm } from "../params/paramsStore";
import { useAppState } from "../store/hooks";
import type { PlayInfo } from "../api/types";
import { currentPlay, playGroups, playList, showGroups } from "../strategy/plays";
import { choosePlay, ensurePlays, usePlays } from "../strategy/playsStore";

/** The options of a play select: grouped "Built-in" / "Team" when the team has plays. */
export function PlayOptions({ list }: { list: readonly PlayInfo[] }) {
  const groups = playGroups(list);
  const option = (p: PlayInfo) => (
    <option key={p.name} value={p.name} title={p.description || undefined} data-source={p.source}>
      {p.title}
    </option>
  );
  if (!showGroups(groups)) return <>{list.map(option)}</>;
  return (
    <>
      {groups.map((g) => (
        <optgroup key={g.label} label={g.label} data-testid={`play-group-${g.label === "Team" ? "team" : "builtin"}`}>
          {g.plays.map(option)}
        </optgroup>
      ))}
    </>
  );
}

/**
 * The play of our team: a select labelled "Play" listing the station's plays by title (the
 * team's own plays in a group of their own), the current one selected, its description as
 * tooltip (and as text in the panel variant).
 * Changing it PATCHes `strategy.play`; every browser follows through the pushed parameters.
 * Renders nothing while the station offers no plays.
 */
export function PlaySelector({ variant }: { variant: "bar" | "panel" }) {
  const connected = useAppState((s) => s.connection.status === "connected");
  const values = useAppState((s) => s.params?.values);
  const worldPlay = useAppState((s) => s.world?.strategy?.play ?? null);
  const plays = usePlays();
  const form = useParamForm();

  // Once per (re)connection; a failed fetch (e.g. a station without strategy) is retried on the next one.
  const failed = plays.error !== null;
  useEffect(() => {
    if (connected) void ensurePlays(failed);
  }, [connected]);

  const schemaField = form.groups?.flatMap((g) => g.fields).find((f) => f.id === "strategy.play");
  const current = currentPlay(values, worldPlay, plays.info);
  const list = playList(plays.info, schemaField?.options, current);
  if (list.length === 0) return null;

  const shown = plays.pending ?? current ?? "";
  const chosen = list.find((p) => p.name === shown);
  const desc = chosen?.description || (chosen ? chosen.title : "");
  const id = `play-select-${variant}`;
  const descId = `play-desc-${variant}`;
  return (
    <div className={`play play-${variant}`} data-testid={`play-${variant}`}>
      <label className="play-label" htmlFor={id}>
        Play
      </label>
      <select
        id={id}
        className="play-select"
        aria-label="Play"
        aria-describedby={descId}
        data-testid={id}
        data-value={current ?? ""}
        data-pending={plays.pending ?? ""}
        title={desc}
        value={shown}
        disabled={!connected}
        onChange={(ev) => {
          const p = list.find((x) => x.name === ev.target.value);
          if (p && p.name !== current) void choosePlay(p.name, p.title);
        }}
      >
        {shown === "" && <option value="">—</option>}
        <PlayOptions list={list} />
      </select>
      {variant === "panel" ? (
        <p id={descId} className="play-desc" data-testid="play-description">
          {chosen?.description ?? ""}
        </p>
      ) : (
        <span id={descId} className="sr-only">
          {desc}
        </span>
      )}
    </div>
  );
}
