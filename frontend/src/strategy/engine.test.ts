import { describe, expect, it } from "vitest";
import type { EngineHealth } from "../api/types";
import { engineHealth } from "../ws/fixtures";
import { engineOf, engineRows, engineSummary } from "./engine";


describe("engine health", () => {
  it("is off when health has no engine", () => {
    expect(engineOf(null)).toBeNull();
    expect(engineOf({})).toBeNull();
    expect(engineOf({ engine: null })).toBeNull();
    expect(engineSummary(null)).toEqual({ text: "off", warn: false });
  });
  it("has a row for every number of the contract", () => {
    const rows = Object.fromEntries(engineRows(engineHealth()).map((r) => [r.key, r]));
    expect(rows.kind!.value).toBe("octave");
    expect(rows.function!.value).toBe("goalkeeper");
    expect(rows.rate!.value).toBe("20.0");
    expect(rows.latency!.value).toBe("3.21 ms / 11.5 ms");
    expect(rows.calls!.value).toBe("1200 / 1190");
    expect(rows.workers!.value).toBe("2: 1 busy / 1 idle");
    expect(rows.fallbacks!.value).toBe("0");
    expect(Object.values(rows).some((r) => r.warn)).toBe(false);
  });
  it("flags failures, fallbacks and a pool without workers, not a busy one", () => {
    const rows = Object.fromEntries(
      engineRows(engineHealth({ timeouts: 3, crashes: 1, fallbacks: 4, busy: 2, idle: 0 })).map((r) => [r.key, r]),
    );
    expect(rows.timeouts!.warn).toBe(true);
    expect(rows.crashes!.warn).toBe(true);
    expect(rows.fallbacks!.warn).toBe(true);
    expect(rows.workers!.warn).toBe(false);
    expect(rows.errors!.warn).toBe(false);
    expect(engineRows(engineHealth({ workers: 0, busy: 0, idle: 0 })).find((r) => r.key === "workers")!.warn).toBe(true);
  });
  it("shows a dash for numbers a backend leaves out", () => {
    const partial = { kind: "numpy", function: "" } as unknown as EngineHealth;
    const rows = Object.fromEntries(engineRows(partial).map((r) => [r.key, r.value]));
    expect(rows.function).toBe("—");
    expect(rows.rate).toBe("—");
    expect(rows.latency).toBe("— / —");
  });
  it("summarises rate, failures and fallbacks", () => {
    expect(engineSummary(engineHealth({ kind: "numpy" }))).toEqual({ text: "numpy 20/s", warn: false });
    expect(engineSummary(engineHealth({ errors: 2, timeouts: 1, fallbacks: 1 }))).toEqual({
      text: "octave 20/s · 3 err · 1 fallback",
      warn: true,
    });
    expect(engineSummary(engineHealth({ last_error: "boom" })).warn).toBe(true);
  });
});
