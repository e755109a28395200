// The Code tab's edit buffers against a stand-in for the station's file routes (GET/PUT
// /api/team/files/{name} with their version rule: a PUT whose base_version is not the version
// on disk is refused with 409; the Playwright spec does the same against the real station).
import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import {
  bufferText,
  editRefusal,
  noteDiskVersions,
  openFile,
  overwriteFile,
  reloadFromDisk,
  resetTeamStore,
  saveFile,
  setBufferText,
  teamStore,
} from "./teamStore";

/** A team folder behind fetch: name -> text; versions are a counter per content. */
function fakeStation(files: Record<string, string>, opts: { denied?: string } = {}) {
  const versions = new Map<string, string>();
  let n = 0;
  const version = (text: string) => {
    if (!versions.has(text)) versions.set(text, `v${++n}`.padEnd(12, "0"));
    return versions.get(text)!;
  };
  const puts: { name: string; text: string; base_version: string | null }[] = [];
  const json = (status: number, body: unknown) => new Response(JSON.stringify(body), { status });
  const fetchMock = vi.fn(async (url: string, init?: RequestInit) => {
    const m = /^\/api\/team\/files\/(.+)$/.exec(url);
    if (!m) return json(404, { detail: "Not Found" });
    const name = decodeURIComponent(m[1]!);
    const method = init?.method ?? "GET";
    if (method === "GET") {
      const text = files[name];
      return text === undefined ? json(404, { detail: `no file ${name}` }) : json(200, { name, text, version: version(text), language: "python" });
    }
    const body = JSON.parse(String(init!.body)) as { text: string; base_version: string | null };
    puts.push({ name, ...body });
    if (opts.denied) return json(403, { detail: opts.denied });
    const now = files[name] === undefined ? null : version(files[name]!);
    if (now !== body.base_version) return json(409, { detail: `${name} changed on disk since version ${body.base_version} (now ${now}): reload it, then edit` });
    files[name] = body.text;
    return json(200, { name, version: version(body.text), saved_at_unix: 1_700_000_000 });
  });
  vi.stubGlobal("fetch", fetchMock);
  return { files, puts, version };
}

const buf = (name: string) => teamStore.getState().buffers[name]!;

beforeEach(() => resetTeamStore());
afterEach(() => vi.unstubAllGlobals());

describe("the edit buffer of a team file", () => {
  it("opens the file, follows edits and saves with the version the edit started from", async () => {
    const st = fakeStation({ "p.py": "X = 1\n" });
    await openFile("p.py");
    expect(teamStore.getState().open).toBe("p.py");
    expect(bufferText("p.py")).toBe("X = 1\n");
    const base = buf("p.py").base;
    expect(base).toBe(st.version("X = 1\n"));
    expect(buf("p.py").dirty).toBe(false);

    setBufferText("p.py", "X = 2\n");
    expect(buf("p.py").dirty).toBe(true);
    setBufferText("p.py", "X = 1\n"); // typed back: nothing to save
    expect(buf("p.py").dirty).toBe(false);
    setBufferText("p.py", "X = 2\n");

    expect(await saveFile("p.py")).toBe(true);
    expect(st.puts).toEqual([{ name: "p.py", text: "X = 2\n", base_version: base }]);
    expect(st.files["p.py"]).toBe("X = 2\n");
    expect(buf("p.py")).toMatchObject({ dirty: false, base: st.version("X = 2\n"), savedVersion: st.version("X = 2\n"), conflict: null });

    // the next save starts from the saved version
    setBufferText("p.py", "X = 3\n");
    expect(await saveFile("p.py")).toBe(true);
    expect(st.puts[1]!.base_version).toBe(st.version("X = 2\n"));
  });

  it("keeps unsaved edits of one file while another is open", async () => {
    fakeStation({ "a.py": "a\n", "b.py": "b\n" });
    await openFile("a.py");
    setBufferText("a.py", "a edited\n");
    await openFile("b.py");
    await openFile("a.py");
    expect(bufferText("a.py")).toBe("a edited\n");
    expect(buf("a.py").dirty).toBe(true);
  });

  it("a conflict (the file changed on disk) keeps the edits; reload from disk takes the disk's text", async () => {
    const st = fakeStation({ "p.py": "X = 1\n" });
    await openFile("p.py");
    setBufferText("p.py", "X = 2  # mine\n");
    st.files["p.py"] = "X = 9  # theirs\n"; // saved by another editor meanwhile

    expect(await saveFile("p.py")).toBe(false);
    expect(buf("p.py").conflict).toMatch(/changed on disk/);
    expect(bufferText("p.py")).toBe("X = 2  # mine\n");
    expect(buf("p.py").dirty).toBe(true);
    expect(st.files["p.py"]).toBe("X = 9  # theirs\n");

    const seq = buf("p.py").docSeq;
    await reloadFromDisk("p.py");
    expect(bufferText("p.py")).toBe("X = 9  # theirs\n");
    expect(buf("p.py")).toMatchObject({ conflict: null, dirty: false, base: st.version("X = 9  # theirs\n") });
    expect(buf("p.py").docSeq).toBe(seq + 1); // the editor takes the new text
  });

  it("after a conflict, overwrite saves mine over the version on disk now", async () => {
    const st = fakeStation({ "p.py": "X = 1\n" });
    await openFile("p.py");
    setBufferText("p.py", "mine\n");
    st.files["p.py"] = "theirs\n";
    expect(await saveFile("p.py")).toBe(false);
    expect(await overwriteFile("p.py")).toBe(true);
    expect(st.files["p.py"]).toBe("mine\n");
    expect(st.puts.at(-1)!.base_version).toBe(st.version("theirs\n"));
    expect(buf("p.py").conflict).toBeNull();
  });

  it("a 403 turns the editor read-only with the station's reason, and nothing more is sent", async () => {
    const st = fakeStation({ "p.py": "X = 1\n" }, { denied: "saving code from another machine needs --allow-code-edit" });
    await openFile("p.py");
    setBufferText("p.py", "X = 2\n");
    expect(await saveFile("p.py")).toBe(false);
    expect(editRefusal(teamStore.getState())).toBe("saving code from another machine needs --allow-code-edit");
    expect(await saveFile("p.py")).toBe(false);
    expect(st.puts).toHaveLength(1);
    expect(bufferText("p.py")).toBe("X = 2\n"); // the edits stay (to copy elsewhere)
  });

  it("GET /api/team's refusal makes it read-only before any save", () => {
    const info = { dir: "/t", api_version: 1, edit: { allowed: false, reason: "only an operator may save code" }, files: [] };
    expect(editRefusal({ info, denied: null })).toBe("only an operator may save code");
    expect(editRefusal({ info: { ...info, edit: { allowed: true, reason: null } }, denied: null })).toBeNull();
  });
});

describe("a file saved elsewhere (health.team_code)", () => {
  it("is taken by a clean buffer, and announced to one with edits; the page's own save is neither", async () => {
    const st = fakeStation({ "a.py": "a1\n", "b.py": "b1\n" });
    await openFile("a.py");
    await openFile("b.py");
    const seen = new Map<string, string>();
    const report = () => Object.entries(st.files).map(([name, text]) => ({ name, version: st.version(text) }));
    noteDiskVersions(report(), seen);

    // the page saves b: the next report shows b's new version, which is the buffer's base
    setBufferText("b.py", "b2\n");
    await saveFile("b.py");
    noteDiskVersions(report(), seen);
    expect(buf("b.py").changedOnDisk).toBe(false);

    // another editor saves a (clean here) and b (edited here)
    setBufferText("b.py", "b3 mine\n");
    st.files["a.py"] = "a2\n";
    st.files["b.py"] = "b2 theirs\n";
    noteDiskVersions(report(), seen);
    await vi.waitFor(() => expect(bufferText("a.py")).toBe("a2\n"));
    expect(buf("b.py").changedOnDisk).toBe(true);
    expect(bufferText("b.py")).toBe("b3 mine\n");
  });
});
