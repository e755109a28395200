import { describe, expect, it } from "vitest";
import { csvCell, toCsv } from "./csv";

describe("toCsv", () => {
  it("writes a header and one row per time, relative to t0, empty cells for gaps", () => {
    const csv = toCsv([100, 100.5], ["robot.blue.1.x", "health.latency.p99_ms"], [[1, null], [null, 2.5]], { t0: 99 });
    expect(csv).toBe("t_s,robot.blue.1.x,health.latency.p99_ms\r\n1,1,\r\n1.5,,2.5\r\n");
  });
  it("can write absolute times and quotes awkward names", () => {
    expect(toCsv([5], ['a,"b"'], [[1]], { absolute: true })).toBe('unix_s,"a,""b"""\r\n5,1\r\n');
  });
  it("leaves non-finite values empty", () => {
    expect(csvCell(Number.NaN)).toBe("");
    expect(csvCell(Infinity)).toBe("");
    expect(csvCell(null)).toBe("");
    expect(csvCell(0)).toBe("0");
  });
});
