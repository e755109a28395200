import { describe, expect, it } from "vitest";
import { ROLE_TAGS, roleColor, roleName, roleTag } from "./roles";

describe("roleTag", () => {
  it("gives the short tag of every role of the contract", () => {
    expect(roleTag("goalkeeper")).toBe("GK");
    expect(roleTag("attacker")).toBe("ATK");
    expect(roleTag("supporter")).toBe("SUP");
    expect(roleTag("defender")).toBe("DEF");
    expect(roleTag("formation")).toBe("FRM");
    expect(roleTag("placer")).toBe("PLC");
    expect(roleTag("kicker")).toBe("KCK");
    expect(roleTag("waiting")).toBe("WAIT");
    expect(roleTag("parked")).toBe("PRK");
    expect(roleTag("operator")).toBe("OP");
    expect(roleTag("substitution")).toBe("SUB");
    // team code: a robot its failed play leaves standing, a team play's robot without a role
    expect(roleTag("stopped")).toBe("STOP");
    expect(roleTag("team")).toBe("TEAM");
    expect(roleColor("stopped")).not.toBe(roleColor("team"));
  });
  it("is case and space tolerant", () => {
    expect(roleTag(" Goalkeeper ")).toBe("GK");
    expect(roleTag("DEFENDER")).toBe("DEF");
  });
  it("falls back to the first three letters of an unknown role", () => {
    expect(roleTag("interceptor")).toBe("INT");
    expect(roleTag("wall_left")).toBe("WAL");
    expect(roleTag("x")).toBe("X");
  });
  it("is null without a role", () => {
    expect(roleTag(null)).toBeNull();
    expect(roleTag(undefined)).toBeNull();
    expect(roleTag("")).toBeNull();
    expect(roleTag("  ")).toBeNull();
  });
  it("keeps every known tag at most 4 characters (they sit next to a robot)", () => {
    for (const tag of Object.values(ROLE_TAGS)) expect(tag.length).toBeLessThanOrEqual(4);
  });
});

describe("roleName and roleColor", () => {
  it("humanises role names", () => {
    expect(roleName("goalkeeper")).toBe("Goalkeeper");
    expect(roleName("ball_placer")).toBe("Ball placer");
    expect(roleName("free-kick-taker")).toBe("Free kick taker");
    expect(roleName(null)).toBe("—");
  });
  it("gives a robot leaving for a substitution a colour of its own (not the supporter's, whose tag looks alike)", () => {
    expect(roleName("substitution")).toBe("Substitution");
    const c = roleColor("substitution");
    expect(c).not.toBe(roleColor(null));
    for (const other of ["supporter", "attacker", "goalkeeper", "waiting", "placer"]) expect(c, other).not.toBe(roleColor(other));
  });
  it("colours attack and defence differently and has a default", () => {
    expect(roleColor("attacker")).not.toBe(roleColor("defender"));
    expect(roleColor("something-new")).toBe(roleColor(null));
  });
});
