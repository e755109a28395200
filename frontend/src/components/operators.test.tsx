// @vitest-environment jsdom
import { act } from "react";
import { describe, expect, it, vi } from "vitest";
import type { DrivingInfo } from "../api/types";
import { commitPatch } from "../params/paramsStore";
import { appStore, initialAppState } from "../store/appStore";
import { domPerTest } from "../testing/dom";
import { health } from "../ws/fixtures";
import { DrivingRequests, OperatorsHealth, readName, refreshMe } from "./OperatorsPanel";

(globalThis as { IS_REACT_ACT_ENVIRONMENT?: boolean }).IS_REACT_ACT_ENVIRONMENT = true;

const t = domPerTest(() => appStore.setState(initialAppState()));
const q = t.q;

const me = { key: "bob@10.0.0.2", name: "bob", role: "operator", address: "10.0.0.2" };
const hold = (over: Partial<DrivingInfo> = {}): DrivingInfo => ({
  team: "blue", key: "alice@10.0.0.1", name: "alice", address: "10.0.0.1", since_unix: 1_700_000_000,
  connected: true, requested_by: null, requested_key: null, requested_unix: null, ...over,
});

type Call = { url: string; method: string; body: unknown; headers: Record<string, string> };

/** fetch answering GET /api/operators with `me` and recording every call. */
function stubFetch(status = 200, answer: unknown = {}): Call[] {
  const calls: Call[] = [];
  vi.stubGlobal("fetch", vi.fn(async (url: string, init: RequestInit) => {
    calls.push({ url, method: init.method ?? "GET", body: init.body ? JSON.parse(String(init.body)) : undefined,
      headers: (init.headers ?? {}) as Record<string, string> });
    const body = url === "/api/operators" ? { me, operators: [], driving: [], actions: [] } : answer;
    return new Response(JSON.stringify(body), { status: url === "/api/operators" ? 200 : status });
  }));
  return calls;
}

async function flush(): Promise<void> {
  await act(async () => {
    await new Promise((r) => setTimeout(r, 0));
  });
}

describe("readName", () => {
  it("reads the name cookie, decoded", () => {
    expect(readName("a=1; touchline_name=Ann%20Lee; b=2")).toBe("Ann Lee");
    expect(readName("a=1")).toBeNull();
    expect(readName("touchline_name=%E0%A4%A")).toBeNull(); // malformed: no name, no crash
  });
});

describe("OperatorsHealth", () => {
  it("lists the pages and the actions; taking over is sent only after the confirmation", async () => {
    const calls = stubFetch();
    await act(async () => refreshMe());
    const h = {
      ...health(),
      operators: [{ session: 1, name: "alice", role: "operator", address: "10.0.0.1", since_unix: 1_700_000_000 },
        { session: 2, name: "bob", role: "operator", address: "10.0.0.2", since_unix: 1_700_000_001 }],
      driving: [hold()],
      operator_actions: [{ seq: 2, time_unix: 1_700_000_002, action: "target", by: "alice (operator at 10.0.0.1)", details: "team=blue, id=1" }],
    };
    act(() => t.root.render(<OperatorsHealth h={h} />));
    expect(q("my-name")?.textContent).toBe("bob");
    expect([...t.host.querySelectorAll('[data-testid="operator-row"]')].map((r) => r.getAttribute("data-name"))).toEqual(["alice", "bob"]);
    expect(q("driving-blue")?.getAttribute("data-holder")).toBe("alice");
    expect(q("driving-blue")?.getAttribute("data-mine")).toBe("false");
    expect(q("driving-yellow")?.textContent).toContain("free");
    expect(q("operator-action")?.textContent).toContain("target");
    calls.length = 0;
    act(() => (q("driving-take-blue") as HTMLButtonElement).click());
    expect(calls).toEqual([]); // nothing sent before the confirmation
    act(() => (q("driving-take-cancel-blue") as HTMLButtonElement).click());
    act(() => (q("driving-take-blue") as HTMLButtonElement).click());
    act(() => (q("driving-take-confirm-blue") as HTMLButtonElement).click());
    await flush();
    expect(calls.map((c) => [c.method, c.url, c.body])).toEqual([["POST", "/api/driving/blue/take", { confirm: true }]]);
  });
});

describe("DrivingRequests", () => {
  it("shows the holder who asks, and accept gives it", async () => {
    const calls = stubFetch();
    await act(async () => refreshMe());
    appStore.setState({ health: { ...health(), driving: [hold({ key: me.key, name: "bob", requested_by: "alice",
      requested_key: "alice@10.0.0.1", requested_unix: 1_700_000_005 })] } });
    act(() => t.root.render(<DrivingRequests />));
    expect(q("driving-request")?.textContent).toContain("alice asks to drive blue");
    calls.length = 0;
    act(() => (q("driving-give") as HTMLButtonElement).click());
    await flush();
    expect(calls.map((c) => [c.method, c.url])).toEqual([["POST", "/api/driving/blue/give"]]);
  });

  it("shows nothing to the others", async () => {
    stubFetch();
    await act(async () => refreshMe());
    appStore.setState({ health: { ...health(), driving: [hold({ requested_by: "carol", requested_key: "c@1", requested_unix: 1 })] } });
    act(() => t.root.render(<DrivingRequests />));
    expect(q("driving-request")).toBeNull();
  });
});

describe("parameter changes carry the version shown", () => {
  it("sends it, and a change refused for being made on an old version says the value now", async () => {
    const detail = [{ loc: ["body", "strategy", "kick_speed_mps"], msg: "changed meanwhile to 4.5 (version 3); your 5.0 was made on version 1: not applied", type: "stale_version" }];
    const calls = stubFetch(409, { detail });
    appStore.setState({ params: { version: 1, values: {} } });
    const msg = await commitPatch({ strategy: { kick_speed_mps: 5.0 } });
    expect(calls[0]?.headers?.["X-Touchline-Params-Version"]).toBe("1");
    expect(msg).toContain("changed meanwhile to 4.5");
  });
});
