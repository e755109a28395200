// Keyboard shortcuts of the whole page (shown by the `?` overlay).

import { selectRobot, setEstop } from "./actions";
import { giveRefereeCommand } from "./actions";
import { fitView } from "./field/viewState";
import { togglePaused } from "./plots/sampler";
import { changeSpeed, isReplaying, seek, shownSpeed, speedStore, step, togglePlay } from "./player/actions";
import { nextSpeed } from "./player/timeline";
import { setTab, TABS, uiStore } from "./store/uiStore";
import { appStore } from "./store/appStore";

export const SHORTCUTS: [string, string][] = [
  ["E", "EMERGENCY STOP (one press, no confirmation)"],
  ["Esc", "deselect robot / cancel ball placement / close menus"],
  ["0 – 9", "select blue robot 0 – 9"],
  ["Shift + 0 – 9", "select yellow robot 0 – 9"],
  ["F", "fit the field into view"],
  ["Space", "pause / resume plots (while replaying: play / pause the log)"],
  ["← / →", "while replaying: one camera frame back / forward"],
  ["Shift + ← / →", "while replaying: 1 s back / forward"],
  ["+ / −", "while replaying: faster / slower (0.1× … 10×, max)"],
  ["H", "internal referee HALT"],
  ["S", "internal referee STOP"],
  ["G", "internal referee FORCE START"],
  ["Alt + 1 – 6", "switch panel: Robots, Params, Plots, Referee, Health, Code"],
  ["L", "large text (projector)"],
  ["?", "this help"],
  ["wheel", "zoom the field at the cursor"],
  ["drag", "pan (middle button anywhere; left button on empty field with no robot selected)"],
  ["click robot, click / drag field", "send it there; dragging sets the heading (direction of the drag)"],
  ["right-click field", "teleport the ball (or the selected robot) there"],
];

function typing(ev: KeyboardEvent): boolean {
  const el = ev.target as HTMLElement | null;
  if (!el) return false;
  const tag = el.tagName;
  return tag === "INPUT" || tag === "TEXTAREA" || tag === "SELECT" || el.isContentEditable;
}

const DIGIT = /^Digit([0-9])$/;

/** The replay's keys (only while a log plays): true when the key was one of them. */
function handleReplayKey(ev: KeyboardEvent): boolean {
  const s = appStore.getState();
  switch (ev.key) {
    case " ":
      void togglePlay();
      return true;
    case "ArrowLeft":
    case "ArrowRight": {
      const dir = ev.key === "ArrowLeft" ? -1 : 1;
      if (ev.shiftKey) {
        const pos = s.world?.replay?.position_s ?? s.player?.position_s ?? 0;
        void seek(pos + dir);
      } else void step(dir);
      return true;
    }
    case "+":
    case "=":
    case "-":
    case "_": {
      const dir = ev.key === "+" || ev.key === "=" ? 1 : -1;
      void changeSpeed(nextSpeed(shownSpeed(s.player, speedStore.getState().pending), dir));
      return true;
    }
    default:
      return false;
  }
}

export function handleKey(ev: KeyboardEvent): boolean {
  if (ev.ctrlKey || ev.metaKey) return false;
  // taken already by the element (the code editor's Escape closing its search, say)
  if (ev.defaultPrevented) return false;
  // Outside text inputs only: "e" is a letter when typing (the E-stop button is always one click away).
  if (typing(ev)) {
    if (ev.key === "Escape") (ev.target as HTMLElement).blur();
    return false;
  }
  // Space and Enter keep activating a focused button (keyboard users).
  if ((ev.key === " " || ev.key === "Enter") && (ev.target as HTMLElement | null)?.tagName === "BUTTON") return false;
  const ui = uiStore.getState();
  if (ev.altKey) {
    const m = DIGIT.exec(ev.code);
    const tab = m ? TABS[Number(m[1]) - 1] : undefined;
    if (tab) {
      setTab(tab.key);
      return true;
    }
    return false;
  }
  if (isReplaying() && handleReplayKey(ev)) return true;
  const m = DIGIT.exec(ev.code);
  if (m) {
    const id = Number(m[1]);
    const team = ev.shiftKey ? "yellow" : "blue";
    const w = appStore.getState().world;
    if (w?.robots.some((r) => r.team === team && r.id === id)) selectRobot({ team, id });
    return true;
  }
  switch (ev.key) {
    case "e":
    case "E":
      void setEstop(true);
      return true;
    case "Escape":
      if (ui.help) uiStore.setState({ help: false });
      else if (ui.placing) uiStore.setState({ placing: null });
      else selectRobot(null);
      window.dispatchEvent(new CustomEvent("touchline:escape"));
      return true;
    case "f":
    case "F":
      fitView();
      return true;
    case " ":
      togglePaused();
      return true;
    case "h":
    case "H":
      void giveRefereeCommand("HALT");
      return true;
    case "s":
    case "S":
      void giveRefereeCommand("STOP");
      return true;
    case "g":
    case "G":
      void giveRefereeCommand("FORCE_START");
      return true;
    case "l":
    case "L":
      uiStore.setState({ largeText: !ui.largeText });
      return true;
    case "?":
      uiStore.setState({ help: !ui.help });
      return true;
    default:
      return false;
  }
}

export function installShortcuts(): () => void {
  const onKey = (ev: KeyboardEvent) => {
    // E repeats (a held key keeps stopping), and so do the replay's frame steps
    const repeats = ev.key === "e" || ev.key === "E" || ev.key === "ArrowLeft" || ev.key === "ArrowRight";
    if (ev.repeat && !repeats) return;
    if (handleKey(ev)) ev.preventDefault();
  };
  window.addEventListener("keydown", onKey);
  return () => window.removeEventListener("keydown", onKey);
}
