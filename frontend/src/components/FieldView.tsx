import { useEffect, useRef, useState } from "react";
import { sendTarget, teleport } from "../actions";
import { SituationBanner } from "./SituationBanner";
import { newInteraction, useFieldDrawing, useFieldInput, type MenuAt } from "../field/useField";
import { cameraColor } from "../field/draw";
import { fitView } from "../field/viewState";
import { useAppState } from "../store/hooks";
import { LAYER_LABELS, toggleLayer, useUi } from "../store/uiStore";

export { fieldStats } from "../field/useField";

type Menu = MenuAt;


function LayersPanel() {
  const layers = useUi((s) => s.layers);
  const [open, setOpen] = useState(false);
  const cams = useAppState((s) => s.world?.cameras.map((c) => c.camera_id).join(",") ?? "");
  const recordedSource = useAppState((s) => s.world?.recorded?.source ?? null);
  const replaying = useAppState((s) => s.world?.replay != null);
  const logCommands = useAppState((s) => (s.world?.recorded?.commands.length ?? 0) > 0);
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
          {layers.recorded && recordedSource !== null && (
            <div className="recorded-legend" data-testid="recorded-legend">
              <i aria-hidden="true" /> recorded by {recordedSource || "the log"}
            </div>
          )}
          {layers.commands && replaying && (
            <div className="commands-legend" data-testid="commands-legend">
              <span>
                <i className="now" aria-hidden="true" /> commanded now
              </span>
              {logCommands && (
                <span>
                  <i className="sent" aria-hidden="true" /> sent then (log)
                </span>
              )}
            </div>
          )}
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

  const ia = useRef(newInteraction()).current;
  useFieldDrawing(wrapRef, canvasRef, ia);
  useFieldInput(canvasRef, ia, setMenu);

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
