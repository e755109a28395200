import { describe, expect, it } from "vitest";
import { fmtFixed, fmtHeading, fmtInt, speedMps } from "./format";

describe("format", () => {
  it("rounds mm to integers without -0 and dashes non-finite", () => {
    expect(fmtInt(1234.6)).toBe("1235");
    expect(fmtInt(-0.2)).toBe("0");
    expect(fmtInt(NaN)).toBe("—");
    expect(fmtInt(null)).toBe("—");
  });
  it("drops the sign of a rounded-away negative", () => {
    expect(fmtFixed(-0.001, 2)).toBe("0.00");
    expect(fmtFixed(-1.256, 2)).toBe("-1.26");
  });
  it("normalises headings to (-180, 180]", () => {
    expect(fmtHeading(0)).toBe("0°");
    expect(fmtHeading(Math.PI)).toBe("180°");
    expect(fmtHeading(-Math.PI / 2)).toBe("-90°");
    expect(fmtHeading((709 * Math.PI) / 180)).toBe("-11°");
  });
  it("computes speed in m/s", () => {
    expect(speedMps(3000, 4000)).toBe(5);
  });
});
