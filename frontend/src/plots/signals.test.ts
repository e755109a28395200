import { describe, expect, it } from "vitest";
import { compareSignals, flattenNumeric, healthSignals, searchSignals, worldSignals } from "./signals";

const world = {
  seq: 7,
  t_capture: 1700000000.1,
  estop: false,
  halt_reason: "",
  ball: { x: 10, y: -5, vx: 300, vy: 400, visible: true, age_s: 0, cameras: [0, 1] },
  robots: [
    {
      team: "blue",
      id: 3,
      x: 100,
      y: 200,
      orientation: 0.5,
      vx: 1000,
      vy: 0,
      omega: 0,
      visible: true,
      age_s: 0.01,
      cameras: [2],
      target: { x: 1, y: 2, orientation: null, source: "operator" },
      controlled: true,
      command: { forward_mps: 0.5, left_mps: 0, angular_radps: 0.1 },
      // fields other engineers add later appear without code changes:
      raw_x: 101,
      controller: { estimated_c: 0.93, reference: { x: 95 } },
      feedback: {
        transport: "sim", ball_contact: true, age_s: 0.008, no_answer: false, last_kick: null, last_kick_age_s: null,
        round_trip_ms: 0.4, commands_sent: 240, answers: 238, loss: 0.008, battery_v: null, kicker_v: null,
      },
    },
  ],
  cameras: [{ camera_id: 0, balls: [{ x: 1, y: 2 }], robots: [] }],
  referee: null,
};

describe("worldSignals", () => {
  const s = worldSignals(world);
  it("names robot fields by team and id, including nested and new fields", () => {
    expect(s.get("robot.blue.3.x")).toBe(100);
    expect(s.get("robot.blue.3.command.forward_mps")).toBe(0.5);
    expect(s.get("robot.blue.3.target.x")).toBe(1);
    expect(s.get("robot.blue.3.raw_x")).toBe(101);
    expect(s.get("robot.blue.3.controller.estimated_c")).toBe(0.93);
    expect(s.get("robot.blue.3.controller.reference.x")).toBe(95);
    expect(s.get("robot.blue.3.visible")).toBe(1);
  });
  it("plots what a robot reports back: ball contact as 0/1, round trip, losses (nulls skipped)", () => {
    expect(s.get("robot.blue.3.feedback.ball_contact")).toBe(1);
    expect(s.get("robot.blue.3.feedback.no_answer")).toBe(0);
    expect(s.get("robot.blue.3.feedback.round_trip_ms")).toBe(0.4);
    expect(s.get("robot.blue.3.feedback.loss")).toBe(0.008);
    expect(s.has("robot.blue.3.feedback.battery_v")).toBe(false);
  });
  it("derives speeds and takes ball fields, skips ids, clocks, raw cameras, strings and nulls", () => {
    expect(s.get("robot.blue.3.speed_mps")).toBe(1);
    expect(s.get("ball.speed_mps")).toBe(0.5);
    expect(s.get("ball.x")).toBe(10);
    expect(s.get("estop")).toBe(0);
    for (const k of s.keys()) {
      expect(k).not.toMatch(/\.id$|seq|t_capture|^cameras|source|target\.orientation|halt_reason/);
    }
    expect([...s.keys()].some((k) => k.startsWith("ball.cameras"))).toBe(false);
  });
});

describe("healthSignals", () => {
  it("keys processors and topics by name, streams by their map key", () => {
    const s = healthSignals({
      ok: true,
      streams: { vision: { packets: 5, rate_hz: 60, errors: 0 } },
      processors: [{ name: "control", measured_hz: 59, configured_hz: null, tick_p99_ms: 0.1 }],
      topics: [{ name: "world", size: 3, capacity: 30 }],
      relay: { command_latency_ms: 2 },
      latency: { p99_ms: 7 },
    });
    expect(s.get("health.streams.vision.rate_hz")).toBe(60);
    expect(s.get("health.processors.control.measured_hz")).toBe(59);
    expect(s.has("health.processors.control.configured_hz")).toBe(false);
    expect(s.get("health.topics.world.size")).toBe(3);
    expect(s.get("health.relay.command_latency_ms")).toBe(2);
    expect(s.get("health.latency.p99_ms")).toBe(7);
    expect(s.has("health.ok")).toBe(false);
  });
});

describe("search and order", () => {
  it("matches every word, case-insensitively", () => {
    const keys = ["robot.blue.3.speed_mps", "robot.blue.3.x", "robot.yellow.3.speed_mps", "health.streams.vision.rate_hz"];
    expect(searchSignals(keys, "Blue 3 SPEED")).toEqual(["robot.blue.3.speed_mps"]);
    expect(searchSignals(keys, "vision rate")).toEqual(["health.streams.vision.rate_hz"]);
    expect(searchSignals(keys, "")).toHaveLength(4);
  });
  it("sorts numerically", () => {
    expect(["robot.blue.10.x", "robot.blue.2.x"].sort(compareSignals)).toEqual(["robot.blue.2.x", "robot.blue.10.x"]);
  });
  it("flattens arrays of plain numbers to nothing", () => {
    const out = new Map<string, number>();
    flattenNumeric({ list: [1, 2, 3] }, "", out);
    expect(out.size).toBe(0);
  });
});

describe("kick signals", () => {
  it("a kick in progress gives ball.kick.* signals by itself (the kicker's id and team are not signals)", () => {
    const kick = {
      robot: { team: "blue", id: 3 }, start_x: 0, start_y: 0, start_t: 1700000000, vx: 3000, vy: 0, speed_mps: 3,
      stop_x: 11250, stop_y: 0, stop_t: 1700000007.5, stop_in_s: 7.4,
    };
    const s = worldSignals({ ...world, ball: { ...world.ball, kick } });
    expect(s.get("ball.kick.speed_mps")).toBe(3);
    expect(s.get("ball.kick.stop_x")).toBe(11250);
    expect(s.get("ball.kick.stop_in_s")).toBe(7.4);
    expect([...s.keys()].some((k) => k.startsWith("ball.kick.robot"))).toBe(false);
    const none = worldSignals({ ...world, ball: { ...world.ball, kick: null } });
    expect([...none.keys()].some((k) => k.startsWith("ball.kick"))).toBe(false);
  });
});

describe("team processors' outputs (world.team)", () => {
  it("are signals team.<processor>.<key>, booleans as 0/1, with no code per processor", () => {
    const s = worldSignals({ ...world, team: { possession: { ours: 0.7, near_ours_mm: 240 }, my_filter: { locked: true, id: 4, bad: Number.NaN } } });
    expect(s.get("team.possession.ours")).toBe(0.7);
    expect(s.get("team.possession.near_ours_mm")).toBe(240);
    expect(s.get("team.my_filter.locked")).toBe(1);
    expect(s.get("team.my_filter.id")).toBe(4); // an output's own name, not a record's identity
    expect(s.has("team.my_filter.bad")).toBe(false);
  });
});
