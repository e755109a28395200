import { useEffect, useRef } from "react";
import type { RobotKey } from "../api/types";
import { sameRobot } from "../api/types";
import { selectRobot, sendTarget } from "../actions";
import { decideClick } from "../field/clickAction";
import { effectiveGeometry } from "../field/defaultGeometry";
import { drawField, MIN_ROBOT_PX } from "../field/draw";
import { hitRadiusMm, hitTestRobot } from "../field/hitTest";
import { canvasToWorld, type FieldTransform } from "../field/transform";
import { registerFieldCanvas, transformFor } from "../field/viewState";
import { appStore, type AppState } from "../store/appStore";

/**
 * The field canvas. Redraws on requestAnimationFrame from the store whenever the state,
 * the size or the device pixel ratio changed; React never re-renders it per frame.
 */
export function FieldView() {
  const wrapRef = useRef<HTMLDivElement>(null);
  const canvasRef = useRef<HTMLCanvasElement>(null);

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
    let lastHover: RobotKey | null = null;
    let hovered: RobotKey | null = null;
    let sizeDirty = true;
    let transform: FieldTransform = transformFor(1, 1, null);
    let raf = 0;

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
      const state = appStore.getState();
      const ratio = window.devicePixelRatio || 1;
      if (!sizeDirty && ratio === dpr && state === lastState && hovered === lastHover) return;
      if (sizeDirty || ratio !== dpr) {
        dpr = ratio;
        canvas.width = Math.round(cssW * dpr);
        canvas.height = Math.round(cssH * dpr);
        sizeDirty = false;
      }
      lastState = state;
      lastHover = hovered;
      transform = transformFor(cssW, cssH, state.geometry);
      if (!ctx) return;
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      drawField(ctx, {
        t: transform,
        geometry: effectiveGeometry(state.geometry),
        waitingForGeometry: state.geometry === null,
        stale: state.connection.status !== "connected",
        world: state.world,
        selected: state.selected,
        hovered,
      });
    };
    raf = requestAnimationFrame(frame);

    const worldPoint = (ev: MouseEvent) => {
      const rect = canvas.getBoundingClientRect();
      const t = transformFor(rect.width, rect.height, appStore.getState().geometry);
      return { t, p: canvasToWorld(t, ev.clientX - rect.left, ev.clientY - rect.top) };
    };

    const onClick = (ev: MouseEvent) => {
      const { t, p } = worldPoint(ev);
      const s = appStore.getState();
      const action = decideClick(s.world?.robots ?? [], s.selected, p, hitRadiusMm(t.scale, MIN_ROBOT_PX + 2));
      if (action.kind === "select") selectRobot(action.robot);
      else if (action.kind === "target") void sendTarget(action.robot, action.point);
    };

    const onMove = (ev: MouseEvent) => {
      const { t, p } = worldPoint(ev);
      const hit = hitTestRobot(appStore.getState().world?.robots ?? [], p, hitRadiusMm(t.scale, MIN_ROBOT_PX + 2));
      const key = hit ? { team: hit.team, id: hit.id } : null;
      if (!sameRobot(key, hovered) && !(key === null && hovered === null)) hovered = key;
      canvas.style.cursor = hit ? "pointer" : appStore.getState().selected ? "crosshair" : "default";
    };
    const onLeave = () => {
      hovered = null;
    };

    canvas.addEventListener("click", onClick);
    canvas.addEventListener("mousemove", onMove);
    canvas.addEventListener("mouseleave", onLeave);
    return () => {
      cancelAnimationFrame(raf);
      ro.disconnect();
      canvas.removeEventListener("click", onClick);
      canvas.removeEventListener("mousemove", onMove);
      canvas.removeEventListener("mouseleave", onLeave);
      registerFieldCanvas(null);
    };
  }, []);

  return (
    <div className="field-wrap" ref={wrapRef}>
      <canvas
        ref={canvasRef}
        data-testid="field-canvas"
        aria-label="Field view: click a robot to select it, then a point to send it there"
        role="img"
      />
    </div>
  );
}
