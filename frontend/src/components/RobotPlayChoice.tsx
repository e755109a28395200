// The selected robot's play (our team only): the team's play, or one of its own, built-in or
// from the team folder (PATCH strategy.robot_plays {"3": name}; the rest keep theirs). Beside
// it the play the station runs for it now, and, when that play failed, that the robot is
// stopped and why.

import { useEffect, useState } from "react";
import type { RobotKey } from "../api/types";
import { useParamForm } from "../params/paramsStore";
import { useAppState } from "../store/hooks";
import { currentPlay, playList, robotPlays } from "../strategy/plays";
import { chooseRobotPlay, ensurePlays, usePlays } from "../strategy/playsStore";
import { stoppedEntry, stoppedText } from "../team/stopped";
import { PlayOptions } from "./PlaySelector";

export function RobotPlayChoice({ robotKey }: { robotKey: RobotKey }) {
  const ourTeam = useAppState((s) => s.world?.strategy?.our_team ?? null);
  const values = useAppState((s) => s.params?.values);
  const worldPlay = useAppState((s) => s.world?.strategy?.play ?? null);
  const runs = useAppState((s) => s.world?.strategy?.robot_plays?.[String(robotKey.id)] ?? null);
  const stopped = useAppState((s) => {
    const e = stoppedEntry(s.world?.strategy, robotKey.team, robotKey.id);
    return e ? stoppedText(e) : null;
  });
  const plays = usePlays();
  const form = useParamForm();
  const [busy, setBusy] = useState(false);
  const connected = useAppState((s) => s.connection.status === "connected");
  useEffect(() => {
    if (connected) void ensurePlays(); // loaded once (the top bar's selector asks too)
  }, [connected]);
  if (ourTeam === null || robotKey.team !== ourTeam) return null;

  const schemaField = form.groups?.flatMap((g) => g.fields).find((f) => f.id === "strategy.play");
  const team = currentPlay(values, worldPlay, plays.info);
  const own = robotPlays(values)[String(robotKey.id)] ?? null;
  const list = playList(plays.info, schemaField?.options, own ?? team);
  if (list.length === 0) return null;
  const title = (name: string | null) => (name ? (list.find((p) => p.name === name)?.title ?? name) : "—");

  return (
    <div className="robot-choice" data-testid="robot-play">
      <label>
        <span>Play</span>
        <select
          data-testid="robot-play-select"
          value={own ?? ""}
          disabled={busy || !values}
          onChange={async (ev) => {
            setBusy(true);
            await chooseRobotPlay(robotKey.id, ev.target.value || null);
            setBusy(false);
          }}
        >
          <option value="">Team's play ({title(team)})</option>
          <PlayOptions list={list} />
        </select>
      </label>
      <span
        className={`choice-state ${own ? "override" : ""} ${stopped ? "choice-stopped" : ""}`}
        data-testid="robot-play-effective"
        data-value={runs ?? ""}
        data-override={own ? "true" : "false"}
        data-stopped={stopped ? "true" : "false"}
        title={stopped ?? (own ? "this robot's own play" : "the team's play")}
      >
        {stopped ? `stopped: ${title(runs ?? own ?? team)} failed` : runs ? `runs ${title(runs)}` : "—"}
        {own ? " · own" : " · team's"}
      </span>
    </div>
  );
}
