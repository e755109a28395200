// The Code tab: the team folder's files (plays, processors, libraries) with their states
// (health.team_code, pushed 4 times a second), the robots stopped because their play failed,
// and the file open in the editor (CodeMirror, loaded on first use) with Save (Ctrl/Cmd+S),
// reload from disk, the conflict and read-only notices, the error's line and traceback.

import { lazy, memo, Suspense, useEffect, useRef, useState } from "react";
import type { TeamFile } from "../api/types";
import { fmtFixed } from "../format";
import { addPlot } from "../plots/sampler";
import { useAppState, useTicker } from "../store/hooks";
import { setTab } from "../store/uiStore";
import { playList } from "../strategy/plays";
import { usePlays } from "../strategy/playsStore";
import {
  currentFiles,
  errorIn,
  groupFiles,
  newPlayName,
  outputRows,
  outputSignal,
  playTemplate,
  reloadedText,
  robotsText,
  stateText,
  tickText,
} from "../team/files";
import { stoppedByPlay, stoppedOf } from "../team/stopped";
import {
  bufferText,
  createFile,
  editRefusal,
  loadTeam,
  noteDiskVersions,
  openFile,
  overwriteFile,
  reloadFromDisk,
  saveFile,
  setBufferText,
  teamStore,
  useTeam,
  type Buffer,
} from "../team/teamStore";
import type { StoppedRobot } from "../api/types";
import { Row } from "./Row";

const CodeEditor = lazy(() => import("./CodeEditor"));

/** The robots a failed play holds still, as a stable string (the world changes 60 times a second). */
function useStopped(): StoppedRobot[] {
  const key = useAppState((s) => {
    const st = s.world?.strategy?.stopped;
    return Array.isArray(st) && st.length > 0 ? JSON.stringify(st) : "";
  });
  return key ? (JSON.parse(key) as StoppedRobot[]) : [];
}

function StateChip({ f }: { f: TeamFile }) {
  const s = stateText(f);
  return (
    <span className={`code-state code-state-${s.tone}`} data-testid={`code-state-${f.name}`} data-state={f.state} title={s.detail}>
      {s.label}
    </span>
  );
}

function FileList({ files, open }: { files: readonly TeamFile[]; open: string | null }) {
  const groups = groupFiles(files);
  if (groups.length === 0) return <p className="muted code-pad">The team folder has no .py or .m files yet: make a new play.</p>;
  return (
    <div className="code-files" data-testid="code-files">
      {groups.map((g) => (
        <div key={g.kind} className="code-group" data-testid={`code-group-${g.kind}`}>
          <h3>{g.label}</h3>
          <ul>
            {g.files.map((f) => (
              <li key={f.name}>
                <button
                  type="button"
                  className={`code-file ${f.name === open ? "code-file-open" : ""}`}
                  aria-current={f.name === open ? "true" : undefined}
                  onClick={() => void openFile(f.name)}
                  data-testid={`code-file-${f.name}`}
                  title={f.description || f.title}
                >
                  <span className="code-file-name">{f.name}</span>
                  <span className="code-file-title">{f.title !== f.play ? f.title : ""}</span>
                  <StateChip f={f} />
                  {f.kind === "play" && f.state === "running" && <span className="code-file-meta num">{robotsText(f.robots)}</span>}
                  {f.kind !== "library" && f.tick_ms_p50 !== null && (
                    <span className="code-file-meta num">{fmtFixed(f.tick_ms_p50, 2)} ms</span>
                  )}
                </button>
              </li>
            ))}
          </ul>
        </div>
      ))}
    </div>
  );
}

function StoppedNotice({ stopped }: { stopped: readonly StoppedRobot[] }) {
  const team = useAppState((s) => s.world?.strategy?.our_team ?? null);
  const groups = stoppedByPlay(stopped);
  if (groups.length === 0) return null;
  return (
    <div className="notice notice-bad" role="alert" data-testid="code-stopped">
      {groups.map((g) => (
        <p key={g.play} data-testid={`code-stopped-${g.play}`} data-ids={g.ids.join(",")}>
          <b>
            {team ?? "our"} {g.ids.join(", ")} stopped
          </b>{" "}
          : play <code>{g.play}</code> failed ({g.reason})
        </p>
      ))}
    </div>
  );
}

function FileDetails({ f, stopped, now }: { f: TeamFile; stopped: readonly StoppedRobot[]; now: number }) {
  const held = stoppedOf(f, stopped);
  const outputs = outputRows(f.outputs);
  return (
    <dl className="details-grid code-details" data-testid="code-details">
      <Row label="state" value={stateText(f).label} testId="code-detail-state" />
      {f.kind !== "library" && <Row label="reloaded" value={`${reloadedText(f.reloaded_at_unix, now)} · ${f.reloads}×`} testId="code-detail-reloaded" />}
      {f.kind !== "library" && <Row label="time a tick" value={tickText(f)} testId="code-detail-tick" />}
      {f.kind === "play" && <Row label="drives" value={robotsText(f.robots)} testId="code-detail-robots" />}
      {held.length > 0 && <Row label="stopped" value={`robots ${held.join(", ")} (the play failed)`} testId="code-detail-stopped" />}
      {f.kind === "play" && <Row label="moved out" value={`${f.moved_out} targets (safety envelope)`} testId="code-detail-moved-out" />}
      {f.kind !== "library" && (
        <Row label="ticks" value={`${f.ticks} · ${f.overruns} over budget${f.late ? ` · ${f.late} late` : ""} · ${f.errors} error${f.errors === 1 ? "" : "s"}`} testId="code-detail-ticks" />
      )}
      {outputs.length > 0 && (
        <>
          <dt>outputs</dt>
          <dd className="code-outputs" data-testid="code-detail-outputs">
            {outputs.map(([k, v]) => (
              <span key={k} className="code-output">
                <span className="num">
                  {k} {v}
                </span>
                <button
                  type="button"
                  className="linkbtn"
                  title={`Plot ${outputSignal(f, k)}`}
                  data-testid={`code-plot-${k}`}
                  onClick={() => {
                    addPlot([outputSignal(f, k)]);
                    setTab("plots");
                  }}
                >
                  plot
                </button>
              </span>
            ))}
          </dd>
        </>
      )}
    </dl>
  );
}

function ErrorBlock({ files, name }: { files: readonly TeamFile[]; name: string }) {
  const e = errorIn(name, files);
  if (!e) return null;
  const where = e.error.line !== null ? `${e.error.file}, line ${e.error.line}` : e.error.file;
  return (
    <div className="code-error" role="alert" data-testid="code-error" data-line={e.error.line ?? ""} data-kind={e.error.kind}>
      <p>
        <b>{e.error.kind}</b> in {where}
        {e.of !== name && <span className="muted-inline"> (while running {e.of})</span>}: {e.error.message.split("\n")[0]}
      </p>
      {e.error.traceback && (
        <pre className="code-traceback" data-testid="code-traceback">
          {e.error.traceback}
        </pre>
      )}
      <p className="muted">Its robots stand still until the file (or the library it failed in) is saved again.</p>
    </div>
  );
}

const EditorBox = memo(function EditorBox({
  b,
  readOnly,
  errorLine,
}: {
  b: Buffer;
  readOnly: boolean;
  errorLine: number | null;
}) {
  return (
    <Suspense fallback={<div className="code-editor code-editor-loading">loading the editor…</div>}>
      <CodeEditor
        name={b.name}
        docSeq={b.docSeq}
        getText={() => bufferText(b.name)}
        language={b.language}
        readOnly={readOnly}
        errorLine={errorLine}
        onChange={(text) => setBufferText(b.name, text)}
        onSave={() => void saveFile(b.name)}
      />
    </Suspense>
  );
});

function EditorPane({ b, files, refusal }: { b: Buffer; files: readonly TeamFile[]; refusal: string | null }) {
  const err = errorIn(b.name, files);
  // the line only when it is this file's (a play failing in a library: the library's line)
  const line = err && err.error.file === b.name ? err.line : null;
  const ro = refusal !== null;
  let status = "";
  if (b.loading) status = "loading…";
  else if (b.saving) status = "saving…";
  else if (b.dirty) status = "unsaved changes";
  else if (b.savedVersion && b.savedVersion === b.base) status = "saved";
  return (
    <div className="code-editor-pane" data-testid="code-editor-pane">
      <div className="code-toolbar">
        <b className="code-open-name">{b.name}</b>
        <span className="muted-inline num" data-testid="code-version" title="the version on disk this edit started from">
          {b.base ?? ""}
        </span>
        <span className={`code-status ${b.dirty ? "code-status-dirty" : ""}`} data-testid="code-save-status" data-dirty={b.dirty ? "true" : "false"}>
          {status}
        </span>
        <span className="grow" />
        <button
          type="button"
          className="btn btn-small"
          onClick={() => void reloadFromDisk(b.name)}
          disabled={b.loading || b.saving}
          data-testid="code-reload"
          title="Take the file as it is on disk now (unsaved changes are lost)"
        >
          Reload from disk
        </button>
        <button
          type="button"
          className="btn btn-small btn-primary"
          onClick={() => void saveFile(b.name)}
          disabled={ro || b.loading || b.saving || b.base === null}
          data-testid="code-save"
          title={ro ? refusal : "Save to the team folder; the station reloads it (Ctrl+S / Cmd+S)"}
        >
          Save
        </button>
      </div>
      {ro && (
        <p className="notice" data-testid="code-readonly">
          Read-only: {refusal}
        </p>
      )}
      {b.conflict && (
        <div className="notice notice-bad" role="alert" data-testid="code-conflict">
          <p>Not saved: {b.conflict}</p>
          <div className="row">
            <button type="button" className="btn btn-small" onClick={() => void reloadFromDisk(b.name)} data-testid="code-conflict-reload">
              Reload from disk
            </button>
            <button type="button" className="btn btn-small" onClick={() => void overwriteFile(b.name)} data-testid="code-conflict-overwrite" disabled={ro}>
              Overwrite with mine
            </button>
          </div>
        </div>
      )}
      {!b.conflict && b.changedOnDisk && (
        <div className="notice" data-testid="code-changed-on-disk">
          <p>{b.name} was changed on disk since you began editing.</p>
          <button type="button" className="btn btn-small" onClick={() => void reloadFromDisk(b.name)}>
            Reload from disk
          </button>
        </div>
      )}
      {b.error && (
        <p className="notice notice-bad" data-testid="code-save-error">
          {b.error}
        </p>
      )}
      {b.base !== null && <EditorBox b={b} readOnly={ro} errorLine={line} />}
    </div>
  );
}

function NewPlay({ files, onDone }: { files: readonly TeamFile[]; onDone: () => void }) {
  const [raw, setRaw] = useState("");
  const [language, setLanguage] = useState<"python" | "octave">("python");
  const [busy, setBusy] = useState(false);
  const plays = usePlays();
  const names = playList(plays.info, undefined, null).map((p) => p.name);
  const check = newPlayName(
    raw,
    language,
    files.map((f) => f.name),
    names,
  );
  const submit = async () => {
    if (!check.name) return;
    setBusy(true);
    const ok = await createFile(check.name, playTemplate(check.name, language));
    setBusy(false);
    if (ok) onDone();
  };
  return (
    <form
      className="code-new row"
      data-testid="code-new-form"
      onSubmit={(ev) => {
        ev.preventDefault();
        void submit();
      }}
    >
      <input
        className="text grow"
        placeholder="name, e.g. my_drill"
        value={raw}
        onChange={(ev) => setRaw(ev.target.value)}
        aria-label="New play's name"
        data-testid="code-new-name"
        autoFocus
      />
      <select value={language} onChange={(ev) => setLanguage(ev.target.value as "python" | "octave")} aria-label="Language" data-testid="code-new-language">
        <option value="python">Python</option>
        <option value="octave">Octave</option>
      </select>
      <button type="submit" className="btn btn-small" disabled={busy || !check.name} data-testid="code-new-create">
        Create {check.name ?? ""}
      </button>
      <button type="button" className="btn btn-small" onClick={onDone}>
        Cancel
      </button>
      {raw && check.error && <span className="pfield-msg" data-testid="code-new-error">{check.error}</span>}
    </form>
  );
}

export default function CodePanel() {
  const connected = useAppState((s) => s.connection.status === "connected");
  const healthFiles = useAppState((s) => s.health?.team_code);
  const info = useTeam((s) => s.info);
  const loadError = useTeam((s) => s.error);
  const open = useTeam((s) => s.open);
  const buffer = useTeam((s) => (s.open ? (s.buffers[s.open] ?? null) : null));
  const refusal = useTeam((s) => editRefusal(s));
  const stopped = useStopped();
  const now = useTicker(true, 1000) / 1000;
  const [creating, setCreating] = useState(false);
  const files = currentFiles(healthFiles, info?.files);

  useEffect(() => {
    if (connected) void loadTeam();
  }, [connected]);

  // Ctrl/Cmd+S anywhere on the tab saves the open file (in the editor, the editor's own key)
  useEffect(() => {
    const onKey = (ev: KeyboardEvent) => {
      if (!(ev.ctrlKey || ev.metaKey) || ev.key.toLowerCase() !== "s" || ev.defaultPrevented) return;
      const name = teamStore.getState().open;
      if (!name) return;
      ev.preventDefault();
      void saveFile(name);
    };
    window.addEventListener("keydown", onKey);
    return () => window.removeEventListener("keydown", onKey);
  }, []);

  // a file saved elsewhere: a clean buffer takes it, one with edits is told
  const seen = useRef(new Map<string, string>()).current;
  useEffect(() => noteDiskVersions(files, seen), [files, seen]);

  // open a play at first (the one in use, else the first) so the tab is not empty
  const worldPlay = useAppState((s) => s.world?.strategy?.play ?? null);
  useEffect(() => {
    if (open !== null || files.length === 0) return;
    const inUse = files.find((f) => f.play !== null && f.play === worldPlay);
    const first = groupFiles(files)[0]?.files[0];
    const pick = inUse ?? first;
    if (pick) void openFile(pick.name);
  }, [open, files, worldPlay]);

  if (!info && loadError) {
    return (
      <section className="code-panel" data-testid="code-panel">
        <p className="notice">This station does not show team code ({loadError}).</p>
      </section>
    );
  }
  const openFileInfo = files.find((f) => f.name === open) ?? null;
  return (
    <section className="code-panel" aria-label="Team code" data-testid="code-panel">
      <div className="code-head row">
        <span className="grow code-dir" title="The team folder (make run TEAM=path, --team-dir)" data-testid="code-dir">
          {info ? info.dir : "…"}
          {info && <span className="muted-inline"> · API v{info.api_version}</span>}
        </span>
        <button type="button" className="btn btn-small" onClick={() => setCreating((v) => !v)} disabled={refusal !== null} data-testid="code-new" title={refusal ?? "Make a new play from a small template"}>
          New play
        </button>
      </div>
      {creating && <NewPlay files={files} onDone={() => setCreating(false)} />}
      <StoppedNotice stopped={stopped} />
      <FileList files={files} open={open} />
      {openFileInfo && <FileDetails f={openFileInfo} stopped={stopped} now={now} />}
      {open && <ErrorBlock files={files} name={open} />}
      {buffer && <EditorPane b={buffer} files={files} refusal={refusal} />}
    </section>
  );
}
