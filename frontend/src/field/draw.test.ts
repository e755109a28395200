import { describe, expect, it } from "vitest";
import type { RefereeCommand, Robot, StrategyState } from "../api/types";
import { geometry, referee, replayClock, world } from "../ws/fixtures";
import { roleColor } from "../strategy/roles";
import type { RecordedWorld } from "../api/types";
import {
  ALL_LAYERS,
  COLORS,
  drawField,
  chipLanding,
  commandVelocity,
  drawRecorded,
  drawRecordedCommands,
  stoppedBanners,
  flyingLabel,
  KICK_CROSS_PX,
  KICK_DASH,
  kickMarks,
  RECORDED_DASH,
  roleTagPx,
  type DrawInput,
} from "./draw";
import { robot } from "./testRobots";
import { makeTransform, worldToCanvas } from "./transform";

/** A 2D context that records what is drawn: method calls with their arguments, text drawn. */
function fakeCtx() {
  const calls: { name: string; args: unknown[]; style: unknown; dash: number }[] = [];
  // style: the stroke style for stroke calls, the fill style for everything else.
  const state: Record<string | symbol, unknown> = {};
  let dash = 0;
  const ctx = new Proxy(state, {
    get(target, prop) {
      if (prop in target) return target[prop];
      if (prop === "measureText") return (s: string) => ({ width: s.length * 7 });
      if (prop === "setLineDash") return (d: number[]) => (dash = d.length);
      return (...args: unknown[]) => {
        const name = String(prop);
        calls.push({ name, args, style: name === "stroke" ? target.strokeStyle : target.fillStyle, dash });
      };
    },
    set(target, prop, value) {
      target[prop] = value;
      return true;
    },
  }) as unknown as CanvasRenderingContext2D;
  return { ctx, calls };
}

const t = makeTransform(1200, 900, { halfX: 6300, halfY: 4800 });
const strategy: StrategyState = {
  play: "match",
  situation: "running",
  situation_text: "Game running",
  our_team: "blue",
  our_side: "negative-x",
  side_from_referee: false,
  tick_ms: 1.2,
  robot_plays: {},
  stopped: [],
};

function input(robots: Robot[], layers = ALL_LAYERS, extra: Partial<DrawInput> = {}): DrawInput {
  return {
    t,
    geometry,
    waitingForGeometry: false,
    stale: false,
    world: world(1, { robots, strategy }),
    selected: null,
    hovered: null,
    layers,
    ...extra,
  };
}

const ours = [
  robot("blue", 0, -4000, 0, { role: "goalkeeper", path: [{ x: -4300, y: 200 }] }),
  robot("blue", 1, 0, 0, { role: "attacker", path: [{ x: 500, y: 500 }, { x: 1000, y: 0 }], kick: { speed_mps: 5, chip: false }, dribbler: true }),
  robot("blue", 2, -1000, 1000, { role: "defender", path: null }),
];
const theirs = [robot("yellow", 0, 2000, 0, { role: "attacker" })];

describe("drawField: strategy layers", () => {
  it("draws the paths of the robots that have one and a role tag per robot of ours", () => {
    const { ctx, calls } = fakeCtx();
    const counts = drawField(ctx, input([...ours, ...theirs]));
    expect(counts.paths).toBe(2);
    expect(counts.roles).toBe(3); // not the yellow robot: not ours
    const texts = calls.filter((c) => c.name === "fillText").map((c) => c.args[0]);
    expect(texts).toEqual(expect.arrayContaining(["GK", "ATK", "DEF"]));
    // dashed polylines: robot 1 -> two waypoints
    const dashedLines = calls.filter((c) => c.name === "lineTo" && c.dash > 0);
    expect(dashedLines.length).toBeGreaterThanOrEqual(3);
  });

  it("tags a robot leaving the field for a substitution SUB, in the substitution colour", () => {
    const { ctx, calls } = fakeCtx();
    const counts = drawField(ctx, input([...ours, robot("blue", 5, -300, 4400, { role: "substitution" })]));
    expect(counts.roles).toBe(4);
    const sub = calls.filter((c) => c.name === "fillText" && c.args[0] === "SUB");
    expect(sub).toHaveLength(1);
    expect(sub[0]!.style).toBe(roleColor("substitution"));
  });

  it("draws no path with the paths layer off and no tags with the roles layer off", () => {
    const { ctx, calls } = fakeCtx();
    const counts = drawField(ctx, input(ours, { ...ALL_LAYERS, paths: false, roles: false }));
    expect(counts.paths).toBe(0);
    expect(counts.roles).toBe(0);
    expect(calls.filter((c) => c.name === "fillText").map((c) => c.args[0])).not.toContain("ATK");
  });

  it("tags every robot with a role when the station does not say which team is ours", () => {
    const { ctx } = fakeCtx();
    const counts = drawField(ctx, { ...input([...ours, ...theirs]), world: world(1, { robots: [...ours, ...theirs] }) });
    expect(counts.roles).toBe(4);
  });

  it("renders a world without any strategy field (older backend)", () => {
    const { ctx } = fakeCtx();
    const counts = drawField(ctx, { ...input([]), world: world(1) });
    expect(counts).toEqual({ robots: 2, raw: 0, paths: 0, roles: 0, designated: null, recorded: 0, kickStop: null, otherBalls: 0, stopped: [], commands: 0, recordedCommands: 0 });
  });

  it("marks an armed kicker (rose bar, violet for a chip) and the dribbler (cyan dot)", () => {
    const flat = fakeCtx();
    drawField(flat.ctx, input([ours[1]!]));
    const strokes = flat.calls.filter((c) => c.name === "stroke").map((c) => c.style);
    expect(strokes).toContain("#f43f5e");
    expect(flat.calls.filter((c) => c.name === "fill").map((c) => c.style)).toContain("#22d3ee");
    const chip = fakeCtx();
    drawField(chip.ctx, input([{ ...ours[1]!, kick: { speed_mps: 3, chip: true }, dribbler: false }]));
    expect(chip.calls.filter((c) => c.name === "stroke").map((c) => c.style)).toContain("#c084fc");
    expect(chip.calls.filter((c) => c.name === "fill").map((c) => c.style)).not.toContain("#22d3ee");
  });

  it("marks a robot holding the ball (orange mark at its front) and one that does not answer (dashed red ring)", () => {
    const fb = {
      transport: "sim" as const, ball_contact: true, age_s: 0.01, no_answer: false, last_kick: null, last_kick_age_s: null,
      round_trip_ms: 0.5, commands_sent: 200, answers: 200, loss: 0, battery_v: null, kicker_v: null,
    };
    const r = robot("blue", 2, 0, 0, { orientation: 0, feedback: fb });
    const held = fakeCtx();
    drawField(held.ctx, input([r]));
    const fills = held.calls.filter((c) => c.name === "fill").map((c) => c.style);
    expect(fills).toContain(COLORS.ballContact);
    // the mark sits in front of the robot (heading +x: right of its centre on the canvas)
    const centre = worldToCanvas(t, 0, 0);
    const idx = held.calls.findIndex((c) => c.name === "fill" && c.style === COLORS.ballContact);
    const arc = held.calls.slice(0, idx).reverse().find((c) => c.name === "arc")!;
    expect(Number(arc.args[0])).toBeGreaterThan(centre.x);
    expect(Math.abs(Number(arc.args[1]) - centre.y)).toBeLessThan(1e-6);
    expect(held.calls.filter((c) => c.name === "stroke").map((c) => c.style)).not.toContain(COLORS.noAnswer);

    const free = fakeCtx();
    drawField(free.ctx, input([{ ...r, feedback: { ...fb, ball_contact: false } }, robot("blue", 3, 500, 0)]));
    expect(free.calls.filter((c) => c.name === "fill").map((c) => c.style)).not.toContain(COLORS.ballContact);

    const silent = fakeCtx();
    drawField(silent.ctx, input([{ ...r, feedback: { ...fb, ball_contact: false, no_answer: true } }]));
    const ring = silent.calls.filter((c) => c.name === "stroke" && c.style === COLORS.noAnswer);
    expect(ring).toHaveLength(1);
    expect(ring[0]!.dash).toBe(2);
  });

  it("uses larger role tags in large-text mode", () => {
    expect(roleTagPx(10, true)).toBeGreaterThan(roleTagPx(10, false));
    const small = fakeCtx();
    const large = fakeCtx();
    drawField(small.ctx, input(ours));
    drawField(large.ctx, input(ours, ALL_LAYERS, { largeText: true }));
    const tagHeight = (calls: { name: string; args: unknown[]; style: unknown }[]) =>
      Math.max(...calls.filter((c) => c.name === "fillRect" && c.style === "rgba(15,23,42,0.82)").map((c) => Number(c.args[3])));
    expect(tagHeight(large.calls)).toBeGreaterThan(tagHeight(small.calls));
  });
});

describe("drawField: the ball placement mark", () => {
  const mark = { x: 1500, y: -700 };
  const draw = (command: RefereeCommand, dp = mark as { x: number; y: number } | null, layers = ALL_LAYERS) => {
    const f = fakeCtx();
    const counts = drawField(f.ctx, { ...input([], layers), world: world(1, { referee: referee(command, { designated_position: dp }) }) });
    const centre = worldToCanvas(t, mark.x, mark.y);
    // the mark is a dashed circle centred on the designated position
    const circles = f.calls.filter((c) => c.name === "arc" && c.dash > 0 && c.args[0] === centre.x && c.args[1] === centre.y);
    return { counts, circles: circles.length };
  };

  it("is drawn during a ball placement of either team, at the designated position", () => {
    for (const cmd of ["BALL_PLACEMENT_BLUE", "BALL_PLACEMENT_YELLOW"] as const) {
      const d = draw(cmd);
      expect(d.counts.designated).toEqual(mark);
      expect(d.circles).toBe(1);
    }
  });

  it("is not drawn for a position the game controller sends outside a placement (STOP, timeout, start)", () => {
    for (const cmd of ["STOP", "TIMEOUT_BLUE", "HALT", "DIRECT_FREE_YELLOW", "FORCE_START"] as const) {
      const d = draw(cmd);
      expect(d.counts.designated).toBeNull();
      expect(d.circles).toBe(0);
    }
    expect(draw("HALT", { x: 0, y: 0 }).counts.designated).toBeNull();
  });

  it("is not drawn without a position or with the referee layer off", () => {
    expect(draw("BALL_PLACEMENT_BLUE", null).counts.designated).toBeNull();
    const off = draw("BALL_PLACEMENT_BLUE", mark, { ...ALL_LAYERS, referee: false });
    expect(off.counts.designated).toBeNull();
    expect(off.circles).toBe(0);
  });
});

describe("drawRecorded: the estimate recorded in a replayed log", () => {
  const rec: RecordedWorld = {
    source: "Touchline",
    ball: { x: 300, y: -200 },
    robots: [
      { team: "blue", id: 0, x: -1000, y: 30, orientation: 0 },
      { team: "yellow", id: 0, x: 1040, y: 0, orientation: Math.PI },
    ],
    commands: [],
  };
  const ringsAt = (calls: ReturnType<typeof fakeCtx>["calls"], p: { x: number; y: number }) =>
    calls.filter((c) => c.name === "arc" && c.dash === RECORDED_DASH.length && c.args[0] === p.x && c.args[1] === p.y);

  it("draws a dashed neutral ring per recorded robot and one for the ball, at their recorded places", () => {
    const { ctx, calls } = fakeCtx();
    expect(drawRecorded(ctx, t, rec)).toBe(3);
    for (const o of [...rec.robots, rec.ball!]) expect(ringsAt(calls, worldToCanvas(t, o.x, o.y))).toHaveLength(1);
    const strokes = calls.filter((c) => c.name === "stroke");
    expect(strokes.length).toBeGreaterThanOrEqual(3);
    expect(new Set(strokes.map((c) => c.style))).toEqual(new Set([COLORS.recorded]));
    // distinct from a lost robot (grey) and from both team colours
    expect(COLORS.recorded).not.toBe(COLORS.lost);
    expect(calls.some((c) => c.name === "fill" || c.name === "fillText")).toBe(false);
  });

  it("rings a robot just outside its body, so today's robot under it stays visible", () => {
    const { ctx, calls } = fakeCtx();
    drawRecorded(ctx, t, { ...rec, ball: null });
    const ring = ringsAt(calls, worldToCanvas(t, -1000, 30))[0]!;
    expect(Number(ring.args[2])).toBeGreaterThan(Math.max(10, 90 * t.scale));
  });

  it("skips objects without a finite position and draws nothing for an empty estimate", () => {
    const { ctx, calls } = fakeCtx();
    const n = drawRecorded(ctx, t, { source: "x", ball: null, robots: [{ team: "blue", id: 1, x: NaN, y: 0, orientation: 0 }], commands: [] });
    expect(n).toBe(0);
    expect(calls.filter((c) => c.name === "arc")).toHaveLength(0);
  });

  it("is drawn by drawField in replay with the layer on, and not live or with the layer off", () => {
    const replayWorld = world(1, { recorded: rec });
    const on = fakeCtx();
    expect(drawField(on.ctx, { ...input([]), world: replayWorld }).recorded).toBe(3);
    expect(ringsAt(on.calls, worldToCanvas(t, 1040, 0))).toHaveLength(1);
    const off = fakeCtx();
    expect(drawField(off.ctx, { ...input([], { ...ALL_LAYERS, recorded: false }), world: replayWorld }).recorded).toBe(0);
    expect(ringsAt(off.calls, worldToCanvas(t, 1040, 0))).toHaveLength(0);
    const live = fakeCtx();
    expect(drawField(live.ctx, { ...input([]), world: world(1) }).recorded).toBe(0);
  });

  it("is on by default", () => {
    expect(ALL_LAYERS.recorded).toBe(true);
  });
});

describe("kicks: the line to a kick's predicted stop point", () => {
  const kick = {
    robot: { team: "yellow" as const, id: 3 },
    start_x: -1000, start_y: 0, start_t: 100, vx: 3000, vy: 0, speed_mps: 3.0,
    stop_x: 2500, stop_y: 400, stop_t: 107.5, stop_in_s: 7,
    chip: false, vz: 0, land_x: null, land_y: null, land_t: null,
  };
  const kicked = (k: typeof kick | null = kick) => {
    const w = world(1);
    return { ...w, ball: { ...w.ball!, x: 0, y: 0, kick: k } };
  };

  it("goes from the ball to the stop point, with the kicker and the speed as its label", () => {
    const m = kickMarks(t, { x: 0, y: 0 }, kick);
    expect(m.line).toEqual([worldToCanvas(t, 0, 0), worldToCanvas(t, 2500, 400)]);
    expect(m.stop).toEqual(worldToCanvas(t, 2500, 400));
    expect(m.label).toBe("Y3 3.0 m/s");
    expect(m.labelColor).toBe(COLORS.yellow);
    const anon = kickMarks(t, { x: 0, y: 0 }, { ...kick, robot: null });
    expect(anon.label).toBe("3.0 m/s");
    expect(anon.labelColor).toBe(COLORS.kick);
  });

  it("has no line once the ball is at the stop point", () => {
    expect(kickMarks(t, { x: 2500, y: 400 }, kick).line).toBeNull();
  });

  it("is drawn by drawField, dashed, with a cross at the stop point; not with the layer off or without a kick", () => {
    const on = fakeCtx();
    expect(drawField(on.ctx, { ...input([]), world: kicked() }).kickStop).toEqual({ x: 2500, y: 400 });
    const stop = worldToCanvas(t, 2500, 400);
    const dashed = on.calls.filter((c) => c.name === "stroke" && c.dash === KICK_DASH.length && c.style === COLORS.kick);
    expect(dashed).toHaveLength(1);
    const cross = on.calls.filter((c) => c.name === "moveTo" && c.args[0] === stop.x - KICK_CROSS_PX);
    expect(cross.length).toBeGreaterThanOrEqual(1);
    expect(on.calls.some((c) => c.name === "fillText" && c.args[0] === "Y3 3.0 m/s")).toBe(true);
    const off = fakeCtx();
    expect(drawField(off.ctx, { ...input([], { ...ALL_LAYERS, kicks: false }), world: kicked() }).kickStop).toBeNull();
    expect(off.calls.some((c) => c.name === "fillText" && c.args[0] === "Y3 3.0 m/s")).toBe(false);
    const none = fakeCtx();
    expect(drawField(none.ctx, { ...input([]), world: kicked(null) }).kickStop).toBeNull();
  });

  it("is on by default and has a layer toggle", async () => {
    expect(ALL_LAYERS.kicks).toBe(true);
    const { LAYER_LABELS } = await import("../store/uiStore");
    expect(LAYER_LABELS.some((l) => l.key === "kicks")).toBe(true);
  });
});

describe("several balls and a chipped ball", () => {
  it("draws the other balls faintly, under the ball, and counts them", () => {
    const f = fakeCtx();
    const w = world(1, {
      other_balls: [{ x: 3000, y: -1000, age_s: 0, cameras: [1], detections: 40 }],
    });
    const counts = drawField(f.ctx, { ...input([]), world: { ...w, robots: [] } });
    expect(counts.otherBalls).toBe(1);
    const p = worldToCanvas(t, 3000, -1000);
    expect(f.calls.some((c) => c.name === "arc" && c.args[0] === p.x && c.args[1] === p.y)).toBe(true);
    const off = fakeCtx();
    expect(drawField(off.ctx, { ...input([], { ...ALL_LAYERS, filtered: false }), world: w }).otherBalls).toBe(0);
  });

  it("labels a flying ball with its height", () => {
    const f = fakeCtx();
    const w = world(1);
    drawField(f.ctx, { ...input([]), world: { ...w, ball: { ...w.ball!, z: 450, vz: 1000, flying: true } } });
    expect(flyingLabel(450)).toBe("\u2191" + "0.45 m");
    expect(f.calls.some((c) => c.name === "fillText" && c.args[0] === flyingLabel(450))).toBe(true);
    const ground = fakeCtx();
    drawField(ground.ctx, { ...input([]), world: w });
    expect(ground.calls.some((c) => c.name === "fillText" && String(c.args[0]).endsWith(" m") && String(c.args[0]).startsWith("\u2191"))).toBe(false);
  });
});

describe("a chip's landing point", () => {
  it("is a ring on the kick's line, only for a chip", () => {
    const flat = {
      robot: null, start_x: 0, start_y: 0, start_t: 1, vx: 2000, vy: 0, speed_mps: 2,
      stop_x: 5000, stop_y: 0, stop_t: 6, stop_in_s: 5, chip: false, vz: 0,
      land_x: null, land_y: null, land_t: null,
    };
    expect(chipLanding(flat)).toBeNull();
    const chip = { ...flat, chip: true, vz: 3000, land_x: 1200, land_y: 0, land_t: 1.6 };
    expect(chipLanding(chip)).toEqual({ x: 1200, y: 0 });
    const f = fakeCtx();
    const w = world(1);
    drawField(f.ctx, { ...input([]), world: { ...w, ball: { ...w.ball!, x: 0, y: 0, kick: chip } } });
    const p = worldToCanvas(t, 1200, 0);
    expect(f.calls.some((c) => c.name === "arc" && c.args[0] === p.x && c.args[1] === p.y && c.args[2] === KICK_CROSS_PX)).toBe(true);
  });
});

describe("drawField: robots a failed team-code play holds still", () => {
  const stopped = { ...strategy, stopped: [{ id: 1, play: "pass_drill", reason: "exception at pass_drill.py:12: ZeroDivisionError" }] };
  const robots = [...ours, robot("yellow", 1, 2500, 0)];

  it("rings each of our stopped robots in red and names the play in a banner", () => {
    const { ctx, calls } = fakeCtx();
    const counts = drawField(ctx, { ...input(robots), world: world(1, { robots, strategy: stopped }) });
    // ours only: the yellow robot with the same id is not the one stopped
    expect(counts.stopped).toEqual(["blue 1"]);
    expect(calls.filter((c) => c.name === "stroke" && c.style === COLORS.stopped)).toHaveLength(1);
    expect(calls.filter((c) => c.name === "fillText").map((c) => c.args[0])).toContain("pass_drill failed: blue 1 stopped");
  });

  it("banners each failed play once with its robots, at most two lines", () => {
    const s = (stopped: { id: number; play: string }[]) => stoppedBanners({ our_team: "yellow", stopped });
    expect(s([{ id: 4, play: "b" }, { id: 2, play: "b" }, { id: 1, play: "a" }])).toEqual(["a failed: yellow 1 stopped", "b failed: yellow 2, 4 stopped"]);
    expect(s([{ id: 1, play: "a" }, { id: 2, play: "b" }, { id: 3, play: "c" }])).toEqual(["a failed: yellow 1 stopped", "2 more plays failed: see the Code tab"]);
    expect(s([])).toEqual([]);
  });

  it("marks nothing while every play runs, or when the stopped robot is not on the field", () => {
    const a = fakeCtx();
    expect(drawField(a.ctx, input(robots)).stopped).toEqual([]);
    expect(a.calls.some((c) => c.name === "stroke" && c.style === COLORS.stopped)).toBe(false);
    const b = fakeCtx();
    const gone = { ...strategy, stopped: [{ id: 9, play: "pass_drill", reason: "x" }] };
    expect(drawField(b.ctx, { ...input(robots), world: world(1, { robots, strategy: gone }) }).stopped).toEqual([]);
  });
});

describe("drawField: the commands in replay (what-if)", () => {
  const cmd = (forward_mps: number, left_mps: number) => ({ forward_mps, left_mps, angular_radps: 0 });

  it("turns a robot-frame command into the field's frame", () => {
    const v = commandVelocity({ orientation: Math.PI / 2, command: cmd(1, 0) })!;
    expect(v.vx).toBeCloseTo(0, 9);
    expect(v.vy).toBeCloseTo(1000, 9);
    const w = commandVelocity({ orientation: Math.PI, command: cmd(0, 0.5) })!;
    expect(w.vx).toBeCloseTo(0, 9);
    expect(w.vy).toBeCloseTo(-500, 9);
    expect(commandVelocity({ orientation: 0, command: null })).toBeNull();
  });

  it("draws an arrow per moving command in replay only, and not with the layer off", () => {
    const robots = [robot("blue", 0, 0, 0, { command: cmd(1.5, 0) }), robot("blue", 1, 500, 0, { command: cmd(0, 0) }), robot("blue", 2, 900, 0)];
    const replay = world(1, { robots, strategy, replay: replayClock() });
    const on = fakeCtx();
    expect(drawField(on.ctx, { ...input(robots), world: replay }).commands).toBe(1);
    expect(on.calls.some((c) => c.name === "stroke" && c.style === COLORS.command)).toBe(true);
    const live = fakeCtx();
    expect(drawField(live.ctx, { ...input(robots), world: world(1, { robots, strategy }) }).commands).toBe(0);
    const off = fakeCtx();
    expect(drawField(off.ctx, { ...input(robots, { ...ALL_LAYERS, commands: false }), world: replay }).commands).toBe(0);
  });

  const sent = (id: number, forward_mps: number, left_mps: number) => ({
    team: "blue" as const, id, forward_mps, left_mps, angular_radps: 0, kick_speed_mps: 0, chip: false, dribbler_rpm: 0, age_s: 0.01,
  });

  it("draws the log's own commands as dashed neutral arrows from the robots, turned by their heading", () => {
    // robot 0 heads +y: the log told it 1 m/s forward (an arrow up), control now says +x
    const robots = [robot("blue", 0, 0, 0, { orientation: Math.PI / 2, command: cmd(1, 0) }), robot("blue", 1, 500, 0)];
    const { ctx, calls } = fakeCtx();
    expect(drawRecordedCommands(ctx, t, robots, [sent(0, 1, 0), sent(1, 0, 0), sent(7, 1, 0)])).toBe(1);
    const from = worldToCanvas(t, 0, 0);
    const to = worldToCanvas(t, 0, 500); // 0.5 s of travel along the robot's heading
    const lines = calls.filter((c) => c.name === "lineTo");
    expect(lines.some((c) => Math.abs(Number(c.args[0]) - to.x) < 1e-6 && Math.abs(Number(c.args[1]) - to.y) < 1e-6)).toBe(true);
    expect(calls.some((c) => c.name === "moveTo" && c.args[0] === from.x && c.args[1] === from.y)).toBe(true);
    const stroke = calls.find((c) => c.name === "stroke")!;
    expect(stroke.style).toBe(COLORS.recorded);
    expect(stroke.dash).toBe(RECORDED_DASH.length);
  });

  it("is drawn beside control's arrows in replay with the commands layer, not without it", () => {
    const robots = [robot("blue", 0, 0, 0, { command: cmd(1.5, 0) }), robot("blue", 1, 500, 0, { command: cmd(0, 0) })];
    const recorded = { source: "", ball: null, robots: [], commands: [sent(0, -1, 0), sent(1, 0, 0.8)] };
    const replay = world(1, { robots, strategy, replay: replayClock(), recorded });
    const on = fakeCtx();
    const counts = drawField(on.ctx, { ...input(robots), world: replay });
    expect(counts.commands).toBe(1);
    expect(counts.recordedCommands).toBe(2);
    expect(on.calls.some((c) => c.name === "stroke" && c.style === COLORS.command)).toBe(true);
    expect(on.calls.some((c) => c.name === "stroke" && c.style === COLORS.recorded && c.dash === RECORDED_DASH.length)).toBe(true);
    const off = fakeCtx();
    expect(drawField(off.ctx, { ...input(robots, { ...ALL_LAYERS, commands: false }), world: replay }).recordedCommands).toBe(0);
  });
});
