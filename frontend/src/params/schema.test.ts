import { describe, expect, it } from "vitest";
import {
  changedFields,
  chooserFields,
  decimalsFor,
  errorForField,
  errorsByField,
  formatValue,
  getAt,
  groupResetPatch,
  localError,
  mergePatches,
  parseNumberInput,
  patchFor,
  schemaToForm,
} from "./schema";

// Shaped like GET /api/params/schema (pydantic v2 model_json_schema of StationParams).
const schema = {
  title: "StationParams",
  type: "object",
  properties: {
    team: { $ref: "#/$defs/TeamParams", description: "Team and side" },
    goto: { $ref: "#/$defs/GoToParams", description: "Go-to controller" },
    control: { $ref: "#/$defs/ControlParams", description: "Motion control" },
  },
  $defs: {
    TeamParams: {
      type: "object",
      description: "Which robots are ours.",
      properties: {
        our_team: { default: "blue", enum: ["blue", "yellow"], type: "string", title: "Our Team", description: "the team" },
        demo: { default: true, type: "boolean", description: "demo formations" },
        demo_period_s: { default: 5, type: "number", minimum: 1, maximum: 60, step: 0.5, unit: "s", description: "time" },
      },
    },
    GoToParams: {
      type: "object",
      properties: {
        kp_per_s: { default: 2.5, type: "number", minimum: 0.1, maximum: 10, step: 0.1, unit: "1/s", description: "gain" },
        count: { default: 3, type: "integer", minimum: 1, maximum: 100 },
        limit: { anyOf: [{ type: "number", exclusiveMinimum: 0 }, { type: "null" }], default: null },
      },
    },
    ControlParams: {
      type: "object",
      properties: {
        algorithm: { default: "algorithm1", enum: ["algorithm1", "algorithm2", "proportional"], type: "string" },
        limits: { $ref: "#/$defs/Limits" },
      },
    },
    Limits: {
      type: "object",
      properties: { max_speed_mps: { default: 3, type: "number", minimum: 0.1, maximum: 6, step: 0.1, unit: "m/s" } },
    },
  },
};

describe("schemaToForm", () => {
  const groups = schemaToForm(schema);
  it("makes one group per top-level property, titled by the $ref's description", () => {
    expect(groups.map((g) => g.key)).toEqual(["team", "goto", "control"]);
    expect(groups[0]!.title).toBe("Team and side");
    expect(groups[0]!.description).toBe("Which robots are ours.");
  });
  it("resolves $refs into typed leaves with bounds, unit, step and help", () => {
    const [ourTeam, demo, period] = groups[0]!.fields;
    expect(ourTeam).toMatchObject({ id: "team.our_team", kind: "enum", options: ["blue", "yellow"], default: "blue" });
    expect(demo).toMatchObject({ kind: "boolean", default: true, title: "Demo" });
    expect(period).toMatchObject({ kind: "number", min: 1, max: 60, step: 0.5, unit: "s", path: ["team", "demo_period_s"] });
    const count = groups[1]!.fields[1]!;
    expect(count).toMatchObject({ kind: "integer", step: 1, min: 1, max: 100 });
  });
  it("unwraps Optional (anyOf with null) and exclusive bounds", () => {
    const limit = groups[1]!.fields[2]!;
    expect(limit).toMatchObject({ kind: "number", nullable: true, min: 0, exclusiveMin: true });
    expect(localError(limit, 0)).toBe("must be > 0");
  });
  it("flattens nested models into sections with longer paths", () => {
    const f = groups[2]!.fields.find((x) => x.key === "max_speed_mps")!;
    expect(f.path).toEqual(["control", "limits", "max_speed_mps"]);
    expect(f.section).toBe("limits");
    expect(f.id).toBe("control.limits.max_speed_mps");
  });
  it("returns nothing for junk", () => {
    expect(schemaToForm(null)).toEqual([]);
    expect(schemaToForm({ properties: { x: { $ref: "#/$defs/Missing" } } })[0]!.fields).toEqual([]);
  });
  it("finds filter/controller choosers", () => {
    expect(chooserFields(groups).map((f) => f.id)).toEqual(["control.algorithm"]);
  });
});

describe("patches and values", () => {
  const groups = schemaToForm(schema);
  it("builds a nested partial PATCH for one leaf", () => {
    expect(patchFor(["goto", "kp_per_s"], 3)).toEqual({ goto: { kp_per_s: 3 } });
    expect(mergePatches(patchFor(["a", "b"], 1), patchFor(["a", "c"], 2))).toEqual({ a: { b: 1, c: 2 } });
  });
  it("resets a group to its defaults", () => {
    expect(groupResetPatch(groups[1]!)).toEqual({ goto: { kp_per_s: 2.5, count: 3, limit: null } });
  });
  it("reads values and lists changed fields", () => {
    const values = { team: { our_team: "blue", demo: false, demo_period_s: 5 }, goto: { kp_per_s: 2.5, count: 3, limit: null } };
    expect(getAt(values, ["team", "demo"])).toBe(false);
    expect(getAt(values, ["nope", "x"])).toBeUndefined();
    expect(changedFields(groups, values).map((f) => f.id)).toEqual(["team.demo", "control.algorithm", "control.limits.max_speed_mps"]);
  });
});

describe("422 errors", () => {
  const groups = schemaToForm(schema);
  const kp = groups[1]!.fields[0]!;
  it("maps FastAPI detail locations to field ids", () => {
    const errs = errorsByField({ detail: [{ loc: ["body", "goto", "kp_per_s"], msg: "Input should be less than or equal to 10", type: "less_than_equal" }] });
    expect(errs).toEqual({ "goto.kp_per_s": "Input should be less than or equal to 10" });
    expect(errorForField(errs, kp)).toBe("Input should be less than or equal to 10");
  });
  it("applies a group-level error to its fields and keeps string details", () => {
    expect(errorForField(errorsByField({ detail: [{ loc: ["body", "goto"], msg: "bad group" }] }), kp)).toBe("bad group");
    expect(errorsByField({ detail: "nope" })).toEqual({ "": "nope" });
  });
});

describe("number input", () => {
  const groups = schemaToForm(schema);
  const kp = groups[1]!.fields[0]!;
  it("parses numbers, commas and NaN, rejects junk", () => {
    expect(parseNumberInput(" 3.5 ", "number")).toBe(3.5);
    expect(parseNumberInput("3,5", "number")).toBe(3.5);
    expect(parseNumberInput("1e3", "number")).toBe(1000);
    expect(parseNumberInput("NaN", "number")).toBeNaN();
    expect(parseNumberInput("abc", "number")).toBeNull();
    expect(parseNumberInput("", "number")).toBeNull();
  });
  it("checks bounds locally and formats with the step's decimals", () => {
    expect(localError(kp, 11)).toBe("must be <= 10");
    expect(localError(kp, 5)).toBeNull();
    expect(localError(kp, Number.NaN)).toBe("must be a finite number");
    expect(decimalsFor(kp)).toBe(1);
    expect(formatValue(kp, 2.5)).toBe("2.5");
    expect(formatValue(kp, 2.55)).toBe("2.55");
    expect(formatValue(kp, 3)).toBe("3.0");
  });
});
