// Pure: strategy roles as short tags for the field and the robot table, their full names and
// colours. Unknown roles (the backend may add some) get a tag from their own name.

export const ROLE_TAGS: Readonly<Record<string, string>> = {
  goalkeeper: "GK",
  attacker: "ATK",
  supporter: "SUP",
  defender: "DEF",
  formation: "FRM",
  placer: "PLC",
  kicker: "KCK",
  waiting: "WAIT",
  parked: "PRK",
  operator: "OP",
  substitution: "SUB",
  // a robot held still because its team-code play failed (marked on the field too)
  stopped: "STOP",
  team: "TEAM",
};

function norm(role: string): string {
  return role.trim().toLowerCase().replace(/[\s-]+/g, "_");
}

/** Short tag of a role ("goalkeeper" -> "GK"); null for no role. Unknown: its first 3 letters. */
export function roleTag(role: string | null | undefined): string | null {
  if (typeof role !== "string" || !role.trim()) return null;
  const known = ROLE_TAGS[norm(role)];
  if (known) return known;
  const letters = role.replace(/[^A-Za-z0-9]/g, "");
  return (letters || role.trim()).slice(0, 3).toUpperCase();
}

/** Full name of a role for tooltips and details ("ball_placer" -> "Ball placer"); "—" for none. */
export function roleName(role: string | null | undefined): string {
  if (typeof role !== "string" || !role.trim()) return "—";
  const s = role.trim().replace(/[_-]+/g, " ");
  return s.charAt(0).toUpperCase() + s.slice(1);
}

/** Text colour of a role's tag: keeper and defenders cool, attack warm, set pieces violet,
 * a robot leaving the field for a substitution (a card) orange. */
export function roleColor(role: string | null | undefined): string {
  switch (typeof role === "string" ? norm(role) : "") {
    case "goalkeeper":
      return "#fde68a";
    case "defender":
      return "#93c5fd";
    case "attacker":
      return "#fca5a5";
    case "supporter":
      return "#86efac";
    case "placer":
    case "kicker":
      return "#d8b4fe";
    case "waiting":
    case "parked":
      return "#cbd5e1";
    case "substitution":
      return "#fb923c";
    case "stopped":
      return "#fca5a5";
    default:
      return "#f1f5f9";
  }
}
