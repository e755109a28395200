// The field canvas's two halves: drawing (a frame loop that draws only when something
// changed) and input (pointer, wheel and context menu -> selection, targets, pan and zoom,
// the teleport menu). They share only what the pointer does to the picture.

import { useEffect, type RefObject } from "react";
import type { RobotKey } from "../api/types";
import { sameRobot } from "../api/types";
import { giveRefereeCommand, selectRobot, sendTarget } from "../actions";
import { appStore, type AppState } from "../store/appStore";
import { uiStore, type UiState } from "../store/uiStore";
import { stoppedEntry, stoppedText } from "../team/stopped";
import { decideClick } from "./clickAction";
import { effectiveGeometry } from "./defaultGeometry";
import { drawField, MIN_ROBOT_PX } from "./draw";
import { hitRadiusMm, hitTestRobot } from "./hitTest";
import { Trails } from "./trails";
import { canvasToWorld, type Point } from "./transform";
import { panBy, registerFieldCanvas, transformFor, viewVersion, zoomAt } from "./viewState";

/** Frames the field drew (for window.__touchline.stats and bench/page_fps.mjs). */
export const fieldStats = {
  rafs: 0, draws: 0, robotsDrawn: 0, rawDrawn: 0, pathsDrawn: 0, rolesDrawn: 0, recordedDrawn: 0,
  designatedDrawn: null as { x: number; y: number } | null,
  kickStopDrawn: null as { x: number; y: number } | null,
  /** Our robots the last frame marked as stopped by a failed team-code play ("blue 3"). */
  stoppedDrawn: [] as string[],
  /** Command arrows the last frame drew (replay's what-if). */
  commandsDrawn: 0,
  /** Arrows of the replayed log's own commands the last frame drew (what the robots were told then). */
  recordedCommandsDrawn: 0,
};

/** Pixels a press may move and still count as a click. */
const CLICK_SLOP_PX = 6;

/** What the pointer does to the picture: the hovered robot, a target being dragged. */
export interface Interaction {
  hovered: RobotKey | null;
  drag: { from: Point; to: Point } | null;
  /** the drag changed: draw again */
  dirty: boolean;
}

export const newInteraction = (): Interaction => ({ hovered: null, drag: null, dirty: false });

/** Where the context menu opens: the canvas point and the field point under it. */
export interface MenuAt {
  x: number;
  y: number;
  p: Point;
}

/** Draws the field into ``canvasRef`` sized to ``wrapRef``, on animation frames, only when the
 * world, the view, the layers, the size or the interaction changed. */
export function useFieldDrawing(wrapRef: RefObject<HTMLDivElement | null>, canvasRef: RefObject<HTMLCanvasElement | null>, ia: Interaction): void {
  useEffect(() => {
    const wrap = wrapRef.current;
    const canvas = canvasRef.current;
    if (!wrap || !canvas) return;
    const ctx = canvas.getContext("2d");
    registerFieldCanvas(canvas);

    let cssW = 0;
    let cssH = 0;
    let dpr = 0;
    let lastState: AppState | null = null;
    let lastUi: UiState | null = null;
    let lastView = -1;
    let lastHover: RobotKey | null = null;
    let sizeDirty = true;
    let raf = 0;
    const trails = new Trails(3);

    const measure = () => {
      const rect = wrap.getBoundingClientRect();
      // Fractional CSS size on purpose: clicks and window.__touchline use the same numbers.
      cssW = Math.max(1, rect.width);
      cssH = Math.max(1, rect.height);
      sizeDirty = true;
    };
    measure();
    const ro = new ResizeObserver(measure);
    ro.observe(wrap);

    const frame = () => {
      raf = requestAnimationFrame(frame);
      fieldStats.rafs++;
      const state = appStore.getState();
      const ui = uiStore.getState();
      const ratio = window.devicePixelRatio || 1;
      if (state.world !== lastState?.world && ui.layers.trails) trails.add(performance.now() / 1000, state.world);
      if (
        !sizeDirty &&
        ratio === dpr &&
        state === lastState &&
        ui === lastUi &&
        lastView === viewVersion &&
        ia.hovered === lastHover &&
        !ia.dirty
      )
        return;
      if (sizeDirty || ratio !== dpr) {
        dpr = ratio;
        canvas.width = Math.round(cssW * dpr);
        canvas.height = Math.round(cssH * dpr);
        sizeDirty = false;
      }
      lastState = state;
      lastUi = ui;
      lastView = viewVersion;
      lastHover = ia.hovered;
      ia.dirty = false;
      const transform = transformFor(cssW, cssH, state.geometry);
      if (!ctx) return;
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      const counts = drawField(ctx, {
        t: transform,
        geometry: effectiveGeometry(state.geometry),
        waitingForGeometry: state.geometry === null,
        stale: state.connection.status !== "connected",
        world: state.world,
        selected: state.selected,
        hovered: ia.hovered,
        layers: ui.layers,
        trails: trails.map,
        drag: ia.drag,
        placing: ui.placing,
        largeText: ui.largeText,
      });
      fieldStats.draws++;
      fieldStats.robotsDrawn = counts.robots;
      fieldStats.rawDrawn = counts.raw;
      fieldStats.pathsDrawn = counts.paths;
      fieldStats.rolesDrawn = counts.roles;
      fieldStats.designatedDrawn = counts.designated;
      fieldStats.recordedDrawn = counts.recorded;
      fieldStats.kickStopDrawn = counts.kickStop;
      fieldStats.stoppedDrawn = counts.stopped;
      fieldStats.commandsDrawn = counts.commands;
      fieldStats.recordedCommandsDrawn = counts.recordedCommands;
    };
    raf = requestAnimationFrame(frame);
    return () => {
      cancelAnimationFrame(raf);
      ro.disconnect();
      registerFieldCanvas(null);
    };
  }, [wrapRef, canvasRef, ia]);
}

/** Pointer, wheel and context-menu input on the field canvas. */
export function useFieldInput(canvasRef: RefObject<HTMLCanvasElement | null>, ia: Interaction, openMenu: (m: MenuAt | null) => void): void {
  useEffect(() => {
    const canvas = canvasRef.current;
    if (!canvas) return;
    const local = (ev: MouseEvent) => {
      const rect = canvas.getBoundingClientRect();
      const t = transformFor(rect.width, rect.height, appStore.getState().geometry);
      const px = ev.clientX - rect.left;
      const py = ev.clientY - rect.top;
      return { t, px, py, p: canvasToWorld(t, px, py), rect };
    };

    type Press =
      | { kind: "pan"; x: number; y: number; moved: boolean; pointerId: number; button: number }
      | { kind: "left"; x: number; y: number; p: Point; moved: boolean; pointerId: number };
    let press: Press | null = null;

    const onDown = (ev: PointerEvent) => {
      if (ev.button === 2) return;
      openMenu(null);
      const { t, px, py, p } = local(ev);
      const s = appStore.getState();
      const hit = hitTestRobot(s.world?.robots ?? [], p, hitRadiusMm(t.scale, MIN_ROBOT_PX + 2));
      canvas.setPointerCapture?.(ev.pointerId);
      if (ev.button === 1 || (ev.button === 0 && !hit && !s.selected && !uiStore.getState().placing)) {
        press = { kind: "pan", x: px, y: py, moved: false, pointerId: ev.pointerId, button: ev.button };
        if (ev.button === 1) ev.preventDefault();
        return;
      }
      if (ev.button === 0) press = { kind: "left", x: px, y: py, p, moved: false, pointerId: ev.pointerId };
    };

    const onMove = (ev: PointerEvent) => {
      const { t, px, py, p } = local(ev);
      if (press) {
        const dist = Math.hypot(px - press.x, py - press.y);
        if (dist > CLICK_SLOP_PX) press.moved = true;
        if (press.kind === "pan" && press.moved) {
          panBy(px - press.x, py - press.y, t.scale);
          press.x = px;
          press.y = py;
          canvas.style.cursor = "grabbing";
          return;
        }
        if (press.kind === "left" && press.moved && appStore.getState().selected && !uiStore.getState().placing) {
          ia.drag = { from: press.p, to: p };
          ia.dirty = true;
          return;
        }
      }
      const w = appStore.getState().world;
      const hit = hitTestRobot(w?.robots ?? [], p, hitRadiusMm(t.scale, MIN_ROBOT_PX + 2));
      const key = hit ? { team: hit.team, id: hit.id } : null;
      if (!sameRobot(key, ia.hovered) && !(key === null && ia.hovered === null)) ia.hovered = key;
      // a robot whose play failed says why on hover
      const held = hit ? stoppedEntry(w?.strategy, hit.team, hit.id) : null;
      const tip = held ? `${hit!.team} ${hit!.id}: ${stoppedText(held)}` : "";
      if (canvas.title !== tip) canvas.title = tip;
      canvas.style.cursor = hit ? "pointer" : appStore.getState().selected || uiStore.getState().placing ? "crosshair" : "grab";
    };

    const onUp = (ev: PointerEvent) => {
      const pr = press;
      press = null;
      if (!pr || pr.pointerId !== ev.pointerId) return;
      canvas.releasePointerCapture?.(ev.pointerId);
      const { t, p } = local(ev);
      if (pr.kind === "pan") {
        canvas.style.cursor = "grab";
        return;
      }
      const s = appStore.getState();
      const placing = uiStore.getState().placing;
      if (ia.drag) {
        const d = ia.drag;
        ia.drag = null;
        ia.dirty = true;
        const sel = s.selected;
        if (sel) {
          const heading = Math.atan2(d.to.y - d.from.y, d.to.x - d.from.x);
          void sendTarget(sel, d.from, heading);
        }
        return;
      }
      if (pr.moved) return;
      if (placing) {
        uiStore.setState({ placing: null });
        void giveRefereeCommand(placing, pr.p);
        return;
      }
      const action = decideClick(s.world?.robots ?? [], s.selected, p, hitRadiusMm(t.scale, MIN_ROBOT_PX + 2));
      if (action.kind === "select") selectRobot(action.robot);
      else if (action.kind === "target") void sendTarget(action.robot, action.point);
    };

    const onLeave = () => {
      ia.hovered = null;
    };

    const onWheel = (ev: WheelEvent) => {
      ev.preventDefault();
      const { px, py, rect } = local(ev);
      const factor = Math.exp(-ev.deltaY * (ev.deltaMode === 1 ? 0.05 : 0.0015));
      zoomAt(rect.width, rect.height, appStore.getState().geometry, px, py, factor);
    };

    const onContext = (ev: MouseEvent) => {
      ev.preventDefault();
      const { px, py, p } = local(ev);
      openMenu({ x: px, y: py, p });
    };

    canvas.addEventListener("pointerdown", onDown);
    canvas.addEventListener("pointermove", onMove);
    canvas.addEventListener("pointerup", onUp);
    canvas.addEventListener("pointercancel", onUp);
    canvas.addEventListener("mouseleave", onLeave);
    canvas.addEventListener("wheel", onWheel, { passive: false });
    canvas.addEventListener("contextmenu", onContext);
    return () => {
      canvas.removeEventListener("pointerdown", onDown);
      canvas.removeEventListener("pointermove", onMove);
      canvas.removeEventListener("pointerup", onUp);
      canvas.removeEventListener("pointercancel", onUp);
      canvas.removeEventListener("mouseleave", onLeave);
      canvas.removeEventListener("wheel", onWheel);
      canvas.removeEventListener("contextmenu", onContext);
    };
  }, [canvasRef, ia, openMenu]);
}
