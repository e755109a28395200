// Trails of the last seconds for robots and the ball. Pure (time passed in).

import type { World } from "../api/types";

export class Trails {
  readonly seconds: number;
  readonly minInterval: number;
  private pts = new Map<string, { t: number; x: number; y: number }[]>();
  private lastT = -Infinity;

  constructor(seconds = 3, minInterval = 0.05) {
    this.seconds = seconds;
    this.minInterval = minInterval;
  }

  add(now: number, world: World | null): void {
    if (!world || now - this.lastT < this.minInterval) return;
    this.lastT = now;
    const push = (k: string, x: number, y: number) => {
      if (!Number.isFinite(x) || !Number.isFinite(y)) return;
      let a = this.pts.get(k);
      if (!a) this.pts.set(k, (a = []));
      a.push({ t: now, x, y });
    };
    for (const r of world.robots) if (r.visible) push(`${r.team}-${r.id}`, r.x, r.y);
    if (world.ball?.visible) push("ball", world.ball.x, world.ball.y);
    for (const [k, a] of this.pts) {
      let i = 0;
      while (i < a.length && now - a[i]!.t > this.seconds) i++;
      if (i > 0) a.splice(0, i);
      if (a.length === 0) this.pts.delete(k);
    }
  }

  get map(): ReadonlyMap<string, readonly { x: number; y: number }[]> {
    return this.pts;
  }
}
