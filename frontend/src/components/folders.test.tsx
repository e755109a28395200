// @vitest-environment jsdom
import { act } from "react";
import { afterEach, describe, expect, it, vi } from "vitest";
import type { StationFolder } from "../api/types";
import { appStore, initialAppState } from "../store/appStore";
import { domPerTest } from "../testing/dom";
import { StationFolders } from "./StationFolders";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;

const t = domPerTest(() => appStore.setState(initialAppState()));
const q = t.q;
const connected = { status: "connected" as const, attempt: 0, retryAt: null, lastError: null };

const FOLDERS: StationFolder[] = [
  { name: "scripts_dir", label: "Octave scripts", what: "the .m files", paths: ["/opt/team/octave"], flag: "--scripts-dir", env: "TOUCHLINE_SCRIPTS_DIR" },
  { name: "record_dir", label: "Recordings", what: "live sessions", paths: ["/var/touchline/logs"], flag: "--record-dir", env: "TOUCHLINE_RECORD_DIR" },
  { name: "log_dirs", label: "Log folders", what: "more logs", paths: [], flag: "--log-dir", env: "TOUCHLINE_LOG_DIRS" },
  { name: "state_dir", label: "State", what: "parameters", paths: ["/var/touchline"], flag: "--state-dir", env: "TOUCHLINE_STATE_DIR" },
];

afterEach(() => vi.unstubAllGlobals());

describe("StationFolders", () => {
  it("lists every folder of the answer read-only, with where it is set", async () => {
    const fetchMock = vi.fn(async () => new Response(JSON.stringify({ folders: FOLDERS })));
    vi.stubGlobal("fetch", fetchMock);
    act(() => appStore.setState({ connection: connected }));
    await act(async () => t.root.render(<StationFolders />));
    expect(fetchMock).toHaveBeenCalledTimes(1);
    expect((fetchMock.mock.calls[0] as unknown as [string])[0]).toBe("/api/folders");
    const rows = t.host.querySelectorAll('tr[data-testid^="station-folder-"]');
    expect([...rows].map((r) => r.getAttribute("data-testid"))).toEqual(FOLDERS.map((f) => `station-folder-${f.name}`));
    const scripts = q("station-folder-scripts_dir")!;
    expect(scripts.textContent).toContain("Octave scripts");
    expect(scripts.querySelector('[data-testid="station-folder-paths"]')?.textContent).toBe("/opt/team/octave");
    expect(scripts.textContent).toContain("--scripts-dir");
    expect(scripts.getAttribute("title")).toContain("TOUCHLINE_SCRIPTS_DIR");
    expect(q("station-folder-log_dirs")?.textContent).toContain("none");
    // nothing to type into or press: the page cannot change a folder
    expect(q("station-folders")?.querySelectorAll("input, button, select, textarea").length).toBe(0);
  });

  it("a folder the backend adds shows without a change here", () => {
    const more = [...FOLDERS, { name: "team_code_dir", label: "Team code", what: "the team's processors", paths: ["/opt/team/code"], flag: "--team-code-dir", env: "TOUCHLINE_TEAM_CODE_DIR" }];
    act(() => t.root.render(<StationFolders folders={more} />));
    expect(q("station-folder-team_code_dir")?.textContent).toContain("/opt/team/code");
  });

  it("says why when the answer does not come", async () => {
    vi.stubGlobal("fetch", vi.fn(async () => new Response('{"detail": "this station requires a token to view"}', { status: 401 })));
    act(() => appStore.setState({ connection: connected }));
    await act(async () => t.root.render(<StationFolders />));
    expect(q("station-folders")?.querySelector('[role="alert"]')?.textContent).toContain("token");
  });

  it("asks nothing before the station is connected", async () => {
    const fetchMock = vi.fn(async () => new Response("{}"));
    vi.stubGlobal("fetch", fetchMock);
    await act(async () => t.root.render(<StationFolders />));
    expect(fetchMock).not.toHaveBeenCalled();
    expect(q("station-folders")?.textContent).toContain("Loading");
  });
});
