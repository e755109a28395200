// The Code tab's state outside React: the team folder (GET /api/team), the file open in the
// editor and one edit buffer per opened file (unsaved edits survive switching files), and the
// actions: open, save (PUT with the version the edit started from), reload from disk,
// overwrite after a conflict, create a new play. The text itself is kept out of the store
// (it changes on every key press); the store says only whether it differs from the disk.

import { useSyncExternalStore } from "react";
import { ApiError, getTeam, getTeamFile, putTeamFile } from "../api/http";
import type { TeamCode } from "../api/types";
import { createStore } from "../store/createStore";
import { pushToast } from "../store/toasts";
import { saveOutcome } from "./save";

export type Language = "python" | "octave";

export interface Buffer {
  name: string;
  language: Language;
  /** The version on disk this edit started from (null: not loaded yet). */
  base: string | null;
  /** +1 whenever the editor must take the text from the store (opened, reloaded from disk). */
  docSeq: number;
  loading: boolean;
  dirty: boolean;
  saving: boolean;
  /** A 409: the file changed on disk since `base` (the server's message). */
  conflict: string | null;
  /** The file changed on disk while this buffer has unsaved edits (seen in health). */
  changedOnDisk: boolean;
  /** Any other failure of the last load or save (413, 422, the station unreachable). */
  error: string | null;
  /** When the last save from this page was accepted (Unix s) and the version it made. */
  savedAt: number | null;
  savedVersion: string | null;
}

export interface TeamState {
  info: TeamCode | null;
  error: string | null;
  loading: boolean;
  /** The file shown in the editor. */
  open: string | null;
  buffers: Readonly<Record<string, Buffer>>;
  /** Why saving is refused (a 403 on save), beside info.edit's reason. */
  denied: string | null;
}

const initial = (): TeamState => ({ info: null, error: null, loading: false, open: null, buffers: {}, denied: null });

export const teamStore = createStore<TeamState>(initial());

/** Texts of the buffers: what the editor shows (changes on every key press, not in the store). */
const texts = new Map<string, string>();
/** Texts as last loaded from or saved to the disk (the base's text), for `dirty`. */
const diskTexts = new Map<string, string>();

/** For tests: back to nothing loaded. */
export function resetTeamStore(): void {
  texts.clear();
  diskTexts.clear();
  teamStore.setState(initial());
}

export function useTeam<T>(sel: (s: TeamState) => T): T {
  return useSyncExternalStore(
    teamStore.subscribe,
    () => sel(teamStore.getState()),
    () => sel(teamStore.getState()),
  );
}

function patchBuffer(name: string, patch: Partial<Buffer>): void {
  teamStore.setState((s) => {
    const b = s.buffers[name];
    if (!b) return {};
    return { buffers: { ...s.buffers, [name]: { ...b, ...patch } } };
  });
}

function message(e: unknown): string {
  return e instanceof Error ? e.message : String(e);
}

/** Why this page may not save code now (null: it may): a 403 on save, else GET /api/team's word. */
export function editRefusal(s: Pick<TeamState, "info" | "denied">): string | null {
  if (s.denied) return s.denied;
  if (s.info && !s.info.edit.allowed) return s.info.edit.reason ?? "editing code is not allowed from this browser";
  return null;
}

/** GET /api/team (the folder, the API version, whether this browser may edit). */
export async function loadTeam(): Promise<void> {
  if (teamStore.getState().loading) return;
  teamStore.setState({ loading: true });
  try {
    const info = await getTeam();
    teamStore.setState({ info, error: null, loading: false });
  } catch (e) {
    teamStore.setState({ error: message(e), loading: false });
  }
}

/** The text the editor shows for `name` ("" before it is loaded). */
export function bufferText(name: string): string {
  return texts.get(name) ?? "";
}

/** The editor changed the text (every key press): kept here, `dirty` follows. */
export function setBufferText(name: string, text: string): void {
  texts.set(name, text);
  const dirty = text !== (diskTexts.get(name) ?? "");
  const b = teamStore.getState().buffers[name];
  if (b && b.dirty !== dirty) patchBuffer(name, { dirty });
}

function languageOf(name: string): Language {
  return name.endsWith(".m") ? "octave" : "python";
}

async function loadFromDisk(name: string): Promise<boolean> {
  patchBuffer(name, { loading: true, error: null });
  try {
    const f = await getTeamFile(name);
    texts.set(name, f.text);
    diskTexts.set(name, f.text);
    const b = teamStore.getState().buffers[name];
    patchBuffer(name, {
      language: f.language,
      base: f.version,
      docSeq: (b?.docSeq ?? 0) + 1,
      loading: false,
      dirty: false,
      conflict: null,
      changedOnDisk: false,
      error: null,
    });
    return true;
  } catch (e) {
    patchBuffer(name, { loading: false, error: message(e) });
    return false;
  }
}

/** Show `name` in the editor: its buffer as left, or loaded from the station the first time. */
export async function openFile(name: string): Promise<void> {
  const s = teamStore.getState();
  if (s.buffers[name]) {
    teamStore.setState({ open: name });
    return;
  }
  const b: Buffer = {
    name,
    language: languageOf(name),
    base: null,
    docSeq: 0,
    loading: true,
    dirty: false,
    saving: false,
    conflict: null,
    changedOnDisk: false,
    error: null,
    savedAt: null,
    savedVersion: null,
  };
  teamStore.setState({ open: name, buffers: { ...s.buffers, [name]: b } });
  await loadFromDisk(name);
}

/** Throw away the edits of `name` and take the file as it is on disk now. */
export async function reloadFromDisk(name: string): Promise<void> {
  await loadFromDisk(name);
}

async function put(name: string, text: string, base: string | null): Promise<boolean> {
  patchBuffer(name, { saving: true, error: null });
  try {
    const saved = await putTeamFile(name, text, base);
    diskTexts.set(name, text);
    patchBuffer(name, {
      saving: false,
      base: saved.version,
      dirty: (texts.get(name) ?? "") !== text,
      conflict: null,
      changedOnDisk: false,
      savedAt: saved.saved_at_unix,
      savedVersion: saved.version,
    });
    teamStore.setState({ denied: null });
    return true;
  } catch (e) {
    const o = saveOutcome(e);
    patchBuffer(name, { saving: false, conflict: o.kind === "conflict" ? o.message : null, error: o.kind === "error" ? o.message : null });
    if (o.kind === "denied") teamStore.setState({ denied: o.message });
    if (o.kind !== "conflict") pushToast("error", `${name} not saved: ${o.message}`);
    return false;
  }
}

/** Save the buffer of `name` (Ctrl/Cmd+S, the Save button): PUT with the version the edit
 * started from; a 409 keeps the edits and shows the conflict. True when saved. */
export async function saveFile(name: string): Promise<boolean> {
  const s = teamStore.getState();
  const b = s.buffers[name];
  if (!b || b.saving || b.loading || b.base === null) return false;
  if (editRefusal(s)) return false;
  return put(name, texts.get(name) ?? "", b.base);
}

/** After a conflict: save this page's text over what is on disk now (its version read first). */
export async function overwriteFile(name: string): Promise<boolean> {
  const b = teamStore.getState().buffers[name];
  if (!b || b.saving) return false;
  let version: string;
  try {
    version = (await getTeamFile(name)).version;
  } catch (e) {
    if (e instanceof ApiError && e.status === 404) return put(name, texts.get(name) ?? "", null);
    patchBuffer(name, { error: message(e) });
    return false;
  }
  return put(name, texts.get(name) ?? "", version);
}

/**
 * The files as the station reports them now (health.team_code). A file whose version on disk
 * changed since the last report and is not what this buffer is based on was saved elsewhere
 * (another editor, another browser): a clean buffer takes it, one with edits is told.
 * `seen` keeps the versions of the previous report between calls.
 */
export function noteDiskVersions(files: readonly { name: string; version: string }[], seen: Map<string, string>): void {
  const s = teamStore.getState();
  for (const f of files) {
    const before = seen.get(f.name);
    seen.set(f.name, f.version);
    if (before === undefined || before === f.version) continue;
    const b = s.buffers[f.name];
    if (!b || b.loading || b.saving || b.base === null || b.base === f.version) continue;
    if (b.dirty) patchBuffer(f.name, { changedOnDisk: true });
    else void loadFromDisk(f.name);
  }
}

/** Create a new file with `text` (refused with 409 when it exists) and open it. */
export async function createFile(name: string, text: string): Promise<boolean> {
  if (editRefusal(teamStore.getState())) return false;
  try {
    const saved = await putTeamFile(name, text, null);
    texts.set(name, text);
    diskTexts.set(name, text);
    const s = teamStore.getState();
    const b: Buffer = {
      name,
      language: languageOf(name),
      base: saved.version,
      docSeq: (s.buffers[name]?.docSeq ?? 0) + 1,
      loading: false,
      dirty: false,
      saving: false,
      conflict: null,
      changedOnDisk: false,
      error: null,
      savedAt: saved.saved_at_unix,
      savedVersion: saved.version,
    };
    teamStore.setState({ open: name, buffers: { ...s.buffers, [name]: b } });
    void loadTeam();
    return true;
  } catch (e) {
    const o = saveOutcome(e);
    if (o.kind === "denied") teamStore.setState({ denied: o.message });
    pushToast("error", `${name} not created: ${o.message}`);
    return false;
  }
}
