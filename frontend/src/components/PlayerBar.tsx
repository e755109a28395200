// Top bar pieces of the log player and the recorder: the REPLAY badge, the "Logs" dialog and
// the record indicator.

import { useCallback, useEffect, useRef, useState, type ReactNode } from "react";
import type { LogList, Recording } from "../api/types";
import { listLogs, openLog, recordingAction } from "../player/actions";
import { baseName, fmtDuration, fmtMB } from "../player/timeline";
import { appStore } from "../store/appStore";
import { useAppState } from "../store/hooks";

/** True while the station replays a log (from the player, or the world's replay clock). */
export function useReplaying(): boolean {
  return useAppState((s) => s.player?.source === "log" || (s.world?.replay ?? null) !== null);
}

export function ReplayBadge() {
  const replaying = useReplaying();
  const file = useAppState((s) => s.world?.replay?.file ?? s.player?.file ?? "");
  if (!replaying) return null;
  const name = baseName(file);
  return (
    <div
      className="replay-badge"
      data-testid="replay-badge"
      role="status"
      title={`Replaying ${file || "a log"}: this is not live, commands are not sent to robots`}
    >
      REPLAY
      {name && <span className="replay-file">{name}</span>}
    </div>
  );
}

function fmtDate(tUnix: number): string {
  if (!(tUnix > 0)) return "";
  const d = new Date(tUnix * 1000);
  const p = (n: number) => String(n).padStart(2, "0");
  return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${p(d.getHours())}:${p(d.getMinutes())}`;
}

export function LogsDialog({ onClose }: { onClose: () => void }) {
  const player = useAppState((s) => s.player);
  const [logs, setLogs] = useState<LogList | null>(null);
  const [failed, setFailed] = useState(false);
  useEffect(() => {
    let alive = true;
    void listLogs().then((l) => {
      if (!alive) return;
      if (l) setLogs(l);
      else setFailed(true);
    });
    return () => {
      alive = false;
    };
  }, []);
  useEffect(() => {
    const onEsc = () => onClose();
    window.addEventListener("touchline:escape", onEsc);
    return () => window.removeEventListener("touchline:escape", onEsc);
  }, [onClose]);
  // indexing finished with the log open: close
  const loading = player?.loading ?? null;
  const wasLoading = useRef(false);
  useEffect(() => {
    if (loading !== null) wasLoading.current = true;
    else if (wasLoading.current) {
      wasLoading.current = false;
      const p = appStore.getState().player;
      if (p?.source === "log" && !p.error) onClose();
    }
  }, [loading, onClose]);
  const files = logs ? [...logs.files].sort((a, b) => b.modified_unix - a.modified_unix) : [];
  return (
    <div className="overlay" role="dialog" aria-modal="true" aria-label="Open a log" data-testid="logs-dialog" onClick={onClose}>
      <div className="overlay-box" onClick={(ev) => ev.stopPropagation()}>
        <div className="row">
          <h2>Logs</h2>
          <button type="button" className="btn" aria-label="Close" data-testid="logs-close" onClick={onClose}>
            ✕
          </button>
        </div>
        {player?.loading !== null && player?.loading !== undefined && (
          <div className="logs-status" data-testid="logs-loading">
            Indexing {baseName(player.file)}: {Math.round(player.loading * 100)}%
            <progress className="logs-progress" max={1} value={player.loading} />
          </div>
        )}
        {player?.error && (
          <p className="logs-status logs-error" data-testid="logs-error">
            {player.error}
          </p>
        )}
        {player?.warning && (
          <p className="logs-status logs-warning" data-testid="logs-warning">
            {player.warning}
          </p>
        )}
        {!logs && !failed && <p className="muted">Loading the list…</p>}
        {failed && <p className="muted">The station did not give the list of logs.</p>}
        {logs && files.length === 0 && (
          <p className="muted" data-testid="logs-empty">
            No logs in {logs.folders.join(", ") || "the log folders"}.
          </p>
        )}
        {files.length > 0 && (
          <table className="logs-table" data-testid="logs-list">
            <thead>
              <tr>
                <th>file</th>
                <th>size</th>
                <th>modified</th>
                <th />
              </tr>
            </thead>
            <tbody>
              {files.map((f) => (
                <tr key={f.path} data-testid={`log-row-${f.name}`}>
                  <td title={f.path}>{f.name}</td>
                  <td className="num">{fmtMB(f.size_bytes)}</td>
                  <td className="num">{fmtDate(f.modified_unix)}</td>
                  <td>
                    <button
                      type="button"
                      className="btn btn-small"
                      data-testid={`log-open-${f.name}`}
                      disabled={player?.loading !== null && player?.loading !== undefined}
                      onClick={() =>
                        void openLog(f.path).then((ok) => {
                          // opened at once: the timeline takes over; while indexing, stay to show the progress
                          const p = appStore.getState().player;
                          if (ok && p?.source === "log" && p.loading === null && !p.error) onClose();
                        })
                      }
                    >
                      Open
                    </button>
                  </td>
                </tr>
              ))}
            </tbody>
          </table>
        )}
      </div>
    </div>
  );
}

export function LogsControl() {
  const [open, setOpen] = useState(false);
  const close = useCallback(() => setOpen(false), []);
  const loading = useAppState((s) => s.player?.loading ?? null);
  return (
    <>
      <button
        type="button"
        className="btn btn-small"
        data-testid="open-log"
        title="Replay a recorded log"
        onClick={() => setOpen(true)}
      >
        Logs{loading !== null ? ` ${Math.round(loading * 100)}%` : ""}
      </button>
      {open && <LogsDialog onClose={close} />}
    </>
  );
}

export type RecordState = "on" | "off" | "error" | "idle";

export function recordState(rec: Recording | null | undefined): RecordState {
  if (!rec) return "off";
  if (rec.error) return "error";
  if (rec.recording) return "on";
  return rec.enabled ? "idle" : "off";
}

export function RecordIndicator() {
  const rec = useAppState((s) => s.health?.recording ?? null);
  const state = recordState(rec);
  let body: ReactNode;
  let title: string;
  if (state === "on" && rec) {
    body = (
      <>
        <span className="rec-label">REC</span>
        <span className="rec-file">{baseName(rec.file)}</span>
        <span className="num" data-testid="record-size">
          {fmtMB(rec.size_bytes)}
        </span>
        <span className="num" data-testid="record-duration">
          {fmtDuration(rec.duration_s)}
        </span>
      </>
    );
    title = `Recording to ${rec.folder}/${rec.file}: ${rec.records} records${rec.dropped ? `, ${rec.dropped} dropped` : ""}`;
  } else if (state === "error" && rec) {
    body = <span className="rec-label">REC error</span>;
    title = rec.error;
  } else if (state === "idle" && rec) {
    body = <span className="rec-label">rec stopped</span>;
    title = rec.file ? `Not recording (last file ${rec.file})` : "Not recording";
  } else {
    body = <span className="rec-label">rec off</span>;
    title = "The session recorder is disabled";
  }
  return (
    <div className="rec-wrap row" style={{ padding: 0, flexWrap: "nowrap" }}>
      <span className={`rec rec-${state}`} data-testid="record-indicator" data-state={state} title={title}>
        <span className="rec-dot" aria-hidden="true" />
        {body}
      </span>
      {rec?.enabled && state !== "on" && (
        <button
          type="button"
          className="btn btn-small"
          data-testid="record-start"
          title="Start recording the session"
          onClick={() => void recordingAction("start")}
        >
          start
        </button>
      )}
      {rec?.enabled && (
        <button
          type="button"
          className="btn btn-small"
          data-testid="record-new-file"
          title="Close the recording file and start a new one"
          onClick={() => void recordingAction("new-file")}
        >
          new file
        </button>
      )}
    </div>
  );
}
