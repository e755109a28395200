// User actions that talk to the backend and update the store.

import { ApiError, deleteTarget, postEstop, postTarget } from "./api/http";
import type { RobotKey } from "./api/types";
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
    pushToast("info", `${robot.team} ${robot.id} back to demo behaviour`);
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
