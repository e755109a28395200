// User actions that talk to the backend and update the store.

import {
  ApiError,
  deleteTarget,
  postArm,
  postEstop,
  postRefereeCard,
  postRefereeCommand,
  postRefereeEnabled,
  postTarget,
  teleportBall,
  teleportRobot,
  type Card,
} from "./api/http";
import type { RefereeCommand, RobotKey, Team } from "./api/types";
import type { Point } from "./field/transform";
import { appStore } from "./store/appStore";
import { pushToast } from "./store/toasts";

function errorText(e: unknown): string {
  if (e instanceof ApiError) return e.status ? `${e.message} (HTTP ${e.status})` : e.message;
  return e instanceof Error ? e.message : String(e);
}

export function selectRobot(key: RobotKey | null): void {
  appStore.setState({ selected: key });
}

export async function sendTarget(robot: RobotKey, p: Point, orientation?: number): Promise<boolean> {
  try {
    await postTarget(robot.team, robot.id, orientation === undefined ? { x: p.x, y: p.y } : { x: p.x, y: p.y, orientation });
    return true;
  } catch (e) {
    pushToast("error", `Target for ${robot.team} ${robot.id} rejected: ${errorText(e)}`);
    return false;
  }
}

export async function clearTarget(robot: RobotKey): Promise<void> {
  try {
    await deleteTarget(robot.team, robot.id);
    pushToast("info", `${robot.team} ${robot.id} back to the strategy`);
  } catch (e) {
    pushToast("error", `Cannot clear target of ${robot.team} ${robot.id}: ${errorText(e)}`);
  }
}

/** Press the emergency stop (`true`), or release it (`false`): a release is only ever sent
 * after the operator confirmed it in the page's dialog. */
export async function setEstop(active: boolean): Promise<void> {
  try {
    const reply = await postEstop(active, !active);
    // Reflect the answer at once; the next world message confirms it.
    const world = appStore.getState().world;
    if (world && typeof reply?.estop === "boolean" && world.estop !== reply.estop) {
      appStore.setState({ world: { ...world, estop: reply.estop } });
    }
  } catch (e) {
    pushToast("error", `Emergency stop request failed: ${errorText(e)}`);
  }
}

/** Arm (only after the operator confirmed it in the page's dialog) or disarm; a refusal's
 * reason (no vision, the e-stop, a replay) shows as a toast. Resolves to success. */
export async function setArmed(armed: boolean): Promise<boolean> {
  try {
    const reply = await postArm(armed);
    // Reflect the answer at once; the next world message confirms it.
    const world = appStore.getState().world;
    if (world && typeof reply?.armed === "boolean") {
      appStore.setState({ world: { ...world, armed: reply.armed, arming: reply } });
    }
    return true;
  } catch (e) {
    pushToast("error", `${armed ? "Arming refused" : "Disarm failed"}: ${errorText(e)}`);
    return false;
  }
}

/** Give a command to the internal referee; resolves to an error text or null (a toast shows
 * it too). Its new state arrives with the next world message. */
export async function giveRefereeCommand(command: RefereeCommand, at?: { x: number; y: number }): Promise<string | null> {
  try {
    await postRefereeCommand(command, at);
    return null;
  } catch (e) {
    const msg = errorText(e);
    pushToast("error", `Referee ${command}: ${msg}`);
    return msg;
  }
}

/** A card from the internal referee; resolves to an error text or null (a toast shows it too). */
export async function giveRefereeCard(team: Team, card: Card): Promise<string | null> {
  try {
    await postRefereeCard(team, card);
    return null;
  } catch (e) {
    const msg = errorText(e);
    pushToast("error", `Referee ${card === "clear" ? "clear cards" : `${card} card`} for ${team}: ${msg}`);
    return msg;
  }
}

/** Switch the internal referee off; resolves to an error text or null. */
export async function turnInternalRefereeOff(): Promise<string | null> {
  try {
    await postRefereeEnabled(false);
    return null;
  } catch (e) {
    return errorText(e);
  }
}

/** Teleport the ball, or a robot, through the simulator (a toast says why it failed). */
export async function teleport(what: "ball" | RobotKey, p: Point): Promise<void> {
  try {
    if (what === "ball") await teleportBall(p.x, p.y);
    else await teleportRobot(what.team, what.id, p.x, p.y);
  } catch (e) {
    pushToast("error", `Teleport failed: ${errorText(e)}`);
  }
}
