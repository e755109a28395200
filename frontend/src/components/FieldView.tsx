import { useEffect, useRef, useState } from "react";
import type { RobotKey } from "../api/types";
import { sameRobot } from "../api/types";
import { giveRefereeCommand, selectRobot, sendTarget, teleport } from "../actions";
import { SituationBanner } from "./SituationBanner";
import { decideClick } from "../field/clickAction";
import { effectiveGeometry } from "../field/defaultGeometry";
import { cameraColor, drawField, MIN_ROBOT_PX } from "../field/draw";
import { hitRadiusMm, hitTestRobot } from "../field/hitTest";
import { Trails } from "../field/trails";
import { canvasToWorld, type FieldTransform, type Point } from "../field/transform";
import { fitView, panBy, registerFieldCanvas, transformFor, viewVersion, zoomAt } from "../field/viewState";
import { appStore, type AppState } from "../store/appStore";
import { useAppState } from "../store/hooks";
import { LAYER_LABELS, toggleLayer, uiStore, useUi, type UiState } from "../store/uiStore";

/** Frames the field drew (for window.__touchline.stats and bench/page_fps.mjs). */
export const fieldStats = {
  rafs: 0, draws: 0, robotsDrawn: 0, rawDrawn: 0, pathsDrawn: 0, rolesDrawn: 0,
  designatedDrawn: null as { x: number; y: number } | null,
};

/** Pixels a press may move and still count as a click. */
const CLICK_SLOP_PX = 6;

interface Menu {
  x: number;
  y: number;
  p: Point;
}


function LayersPanel() {
  const layers = useUi((s) => s.layers);
  const [open, setOpen] = useState(false);
  const cams = useAppState((s) => s.world?.cameras.map((c) => c.camera_id).join(",") ?? "");
  return (
    <div className="layers" data-testid="layers">
      <div className="layers-buttons">
        <button type="button" className="btn btn-small" onClick={() => setOpen((v) => !v)} aria-expanded={open} data-testid="layers-toggle">
          Layers {open ? "▴" : "▾"}
        </button>
        <button type="button" className="btn btn-small" onClick={fitView} title="Fit the field (F)" data-testid="fit-button">
          Fit
        </button>
      </div>
      {open && (
        <div className="layers-list">
          {LAYER_LABELS.map((l) => (
            <label key={l.key} title={l.help} data-testid={`layer-${l.key}`}>
              <input
                type="checkbox"
                checked={layers[l.key]}
                onChange={() => toggleLayer(l.key)}
                data-testid={`layer-toggle-${l.key}`}
                aria-label={l.label}
              />{" "}
              {l.label}
            </label>
          ))}
          {layers.raw && cams && (
            <div className="cam-legend">
              {cams.split(",").map((c) => (
                <span key={c}>
                  <i style={{ background: cameraColor(Number(c)) }} /> cam {c}
                </span>
              ))}
            </div>
          )}
        </div>
      )}
    </div>
  );
}

/**
 * The field canvas. Redraws on requestAnimationFrame from the stores whenever the state,
 * the view, the size or the device pixel ratio changed; React never re-renders it per frame.
 *
 * Mouse: wheel zooms at the cursor; the middle button pans anywhere; the left button pans on
 * empty field when no robot is selected. With a robot selected, a left click on the field
 * sends it there and a left drag sends it to the press point with the drag's direction as
 * heading. Right click opens the teleport menu.
 */
export function FieldView() {
  const wrapRef = useRef<HTMLDivElement>(null);
  const canvasRef = useRef<HTMLCanvasElement>(null);
  const [menu, setMenu] = useState<Menu | null>(null);

  useEffect(() => {
    const close = () => setMenu(null);
    window.addEventListener("touchline:escape", close);
    return () => window.removeEventListener("touchline:escape", close);
  }, []);

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
    let hovered: RobotKey | null = null;
    let sizeDirty = true;
    let transform: FieldTransform = transformFor(1, 1, null);
    let raf = 0;
    const trails = new Trails(3);
    let drag: { from: Point; to: Point } | null = null;
    let dragDirty = false;

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
        hovered === lastHover &&
        !dragDirty
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
      lastHover = hovered;
      dragDirty = false;
      transform = transformFor(cssW, cssH, state.geometry);
      if (!ctx) return;
      ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
      const counts = drawField(ctx, {
        t: transform,
        geometry: effectiveGeometry(state.geometry),
        waitingForGeometry: state.geometry === null,
        stale: state.connection.status !== "connected",
        world: state.world,
        selected: state.selected,
        hovered,
        layers: ui.layers,
        trails: trails.map,
        drag,
        placing: ui.placing,
        largeText: ui.largeText,
      });
      fieldStats.draws++;
      fieldStats.robotsDrawn = counts.robots;
      fieldStats.rawDrawn = counts.raw;
      fieldStats.pathsDrawn = counts.paths;
      fieldStats.rolesDrawn = counts.roles;
      fieldStats.designatedDrawn = counts.designated;
    };
    raf = requestAnimationFrame(frame);

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
      setMenu(null);
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
          drag = { from: press.p, to: p };
          dragDirty = true;
          return;
        }
      }
      const hit = hitTestRobot(appStore.getState().world?.robots ?? [], p, hitRadiusMm(t.scale, MIN_ROBOT_PX + 2));
      const key = hit ? { team: hit.team, id: hit.id } : null;
      if (!sameRobot(key, hovered) && !(key === null && hovered === null)) hovered = key;
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
      if (drag) {
        const d = drag;
        drag = null;
        dragDirty = true;
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
      hovered = null;
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
      setMenu({ x: px, y: py, p });
    };

    canvas.addEventListener("pointerdown", onDown);
    canvas.addEventListener("pointermove", onMove);
    canvas.addEventListener("pointerup", onUp);
    canvas.addEventListener("pointercancel", onUp);
    canvas.addEventListener("mouseleave", onLeave);
    canvas.addEventListener("wheel", onWheel, { passive: false });
    canvas.addEventListener("contextmenu", onContext);
    return () => {
      cancelAnimationFrame(raf);
      ro.disconnect();
      canvas.removeEventListener("pointerdown", onDown);
      canvas.removeEventListener("pointermove", onMove);
      canvas.removeEventListener("pointerup", onUp);
      canvas.removeEventListener("pointercancel", onUp);
      canvas.removeEventListener("mouseleave", onLeave);
      canvas.removeEventListener("wheel", onWheel);
      canvas.removeEventListener("contextmenu", onContext);
      registerFieldCanvas(null);
    };
  }, []);

  const selected = useAppState((s) => s.selected);

  const teleportHere = async (what: "ball" | "robot") => {
    const m = menu;
    setMenu(null);
    if (!m) return;
    if (what === "ball") await teleport("ball", m.p);
    else if (selected) await teleport(selected, m.p);
  };

  return (
    <div className="field-wrap" ref={wrapRef}>
      <canvas
        ref={canvasRef}
        data-testid="field-canvas"
        aria-label="Field view: click a robot to select it, then a point to send it there"
        role="img"
      />
      <LayersPanel />
      <SituationBanner />
      {menu && (
        <div className="ctxmenu" style={{ left: menu.x, top: menu.y }} role="menu" data-testid="field-menu" onPointerDown={(ev) => ev.stopPropagation()}>
          <div className="ctxmenu-title num">
            {Math.round(menu.p.x)}, {Math.round(menu.p.y)} mm
          </div>
          <button type="button" role="menuitem" data-testid="menu-teleport-ball" onClick={() => void teleportHere("ball")}>
            Teleport ball here
          </button>
          {selected && (
            <button type="button" role="menuitem" data-testid="menu-teleport-robot" onClick={() => void teleportHere("robot")}>
              Teleport {selected.team} {selected.id} here
            </button>
          )}
          {selected && (
            <button
              type="button"
              role="menuitem"
              onClick={() => {
                setMenu(null);
                void sendTarget(selected, menu.p);
              }}
            >
              Send {selected.team} {selected.id} here
            </button>
          )}
          <button type="button" role="menuitem" onClick={() => setMenu(null)}>
            Cancel
          </button>
        </div>
      )}
    </div>
  );
}
