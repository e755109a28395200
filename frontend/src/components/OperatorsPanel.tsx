// Several operators (docs/security.md): who is connected, who drives which team (ask for it,
// give it, take it over after a confirmation), what every operator did, and this page's name.

import { useEffect, useState, useSyncExternalStore } from "react";
import {
  getOperators,
  giveDriving,
  releaseDriving,
  requestDriving,
  takeDriving,
  type Me,
} from "../api/http";
import type { DrivingInfo, Health, Team } from "../api/types";
import { createStore } from "../store/createStore";
import { useAppState } from "../store/hooks";
import { pushToast } from "../store/toasts";

/** The cookie the station reads the operator's name from (/login?name= sets it too). */
export const NAME_COOKIE = "touchline_name";
const ASKED_KEY = "touchline.nameAsked";
const TEAMS: Team[] = ["blue", "yellow"];

export function readName(cookie: string = document.cookie): string | null {
  for (const part of cookie.split(";")) {
    const [k, ...v] = part.trim().split("=");
    if (k === NAME_COOKIE && v.length > 0) {
      try {
        return decodeURIComponent(v.join("=")) || null;
      } catch {
        return null;
      }
    }
  }
  return null;
}

function writeName(name: string): void {
  document.cookie = `${NAME_COOKIE}=${encodeURIComponent(name)}; path=/; max-age=${365 * 24 * 3600}; samesite=strict`;
}

/** Who this page is, as the station sees it (name, role, address, key). */
const meStore = createStore<{ me: Me | null }>({ me: null });

export async function refreshMe(): Promise<void> {
  try {
    meStore.setState({ me: (await getOperators()).me });
  } catch {
    /* the health line says what is wrong with the station */
  }
}

export function useMe(): Me | null {
  return useSyncExternalStore(meStore.subscribe, () => meStore.getState().me, () => meStore.getState().me);
}

const errorText = (e: unknown) => (e instanceof Error ? e.message : String(e));

async function act(what: string, fn: () => Promise<unknown>): Promise<void> {
  try {
    await fn();
  } catch (e) {
    pushToast("error", `${what}: ${errorText(e)}`);
  }
}

/** Asks once (per browser) for the name the other operators see; "local" until then. */
export function NamePrompt() {
  const [asked, setAsked] = useState(() => readName() !== null || localStorage.getItem(ASKED_KEY) === "1");
  const [name, setName] = useState(() => readName() ?? "local");
  useEffect(() => {
    void refreshMe();
  }, []);
  if (asked) return null;
  const save = () => {
    const n = name.trim() || "local";
    writeName(n);
    localStorage.setItem(ASKED_KEY, "1");
    setAsked(true);
    void refreshMe();
  };
  return (
    <form
      className="name-prompt notice"
      data-testid="name-prompt"
      onSubmit={(ev) => {
        ev.preventDefault();
        save();
      }}
    >
      <label>
        Your name for the other operators{" "}
        <input data-testid="name-input" value={name} maxLength={32} onChange={(ev) => setName(ev.target.value)} />
      </label>{" "}
      <button type="submit" className="btn btn-small" data-testid="name-save">
        OK
      </button>
    </form>
  );
}

/** For the holder: someone asks to drive; accept gives it to them. */
export function DrivingRequests() {
  const driving = useAppState((s) => s.health?.driving ?? null);
  const me = useMe();
  const [dismissed, setDismissed] = useState<Record<string, number>>({});
  if (!driving || !me) return null;
  const asks = driving.filter(
    (d) => d.key === me.key && d.requested_by !== null && d.requested_key !== me.key && dismissed[d.team] !== d.requested_unix,
  );
  if (asks.length === 0) return null;
  return (
    <div className="toasts driving-requests">
      {asks.map((d) => (
        <div key={d.team} className="toast toast-info" role="alert" data-testid="driving-request" data-team={d.team}>
          <span>
            {d.requested_by} asks to drive {d.team}
          </span>
          <button type="button" className="btn btn-small" data-testid="driving-give" onClick={() => void act("Give driving", () => giveDriving(d.team as Team))}>
            Accept
          </button>
          <button type="button" aria-label="Dismiss" onClick={() => setDismissed({ ...dismissed, [d.team]: d.requested_unix ?? 0 })}>
            ✕
          </button>
        </div>
      ))}
    </div>
  );
}

const clock = (unix: number) => new Date(unix * 1000).toLocaleTimeString();

function DrivingRow({ team, hold, me }: { team: Team; hold: DrivingInfo | undefined; me: Me | null }) {
  const [confirming, setConfirming] = useState(false);
  const mine = hold !== undefined && me !== null && hold.key === me.key;
  return (
    <tr data-testid={`driving-${team}`} data-holder={hold?.name ?? ""} data-mine={mine ? "true" : "false"}>
      <td className="hname">{team}</td>
      <td>
        {hold ? (
          <>
            <b>{mine ? `you (${hold.name})` : hold.name}</b> <span className="muted">{hold.address} since {clock(hold.since_unix)}</span>
            {!hold.connected && <span className="muted"> · page closed: released soon</span>}
            {hold.requested_by && <span className="muted"> · {hold.requested_by} asks for it</span>}
          </>
        ) : (
          <span className="muted">free: the first who drives takes it</span>
        )}
      </td>
      <td>
        {mine && (
          <button type="button" className="btn btn-small" data-testid={`driving-release-${team}`} onClick={() => void act("Release driving", () => releaseDriving(team))}>
            Release
          </button>
        )}
        {hold && !mine && !confirming && (
          <>
            <button type="button" className="btn btn-small" data-testid={`driving-ask-${team}`} onClick={() => void act("Ask for driving", () => requestDriving(team))}>
              Ask
            </button>{" "}
            <button type="button" className="btn btn-small btn-danger" data-testid={`driving-take-${team}`} onClick={() => setConfirming(true)}>
              Take over…
            </button>
          </>
        )}
        {hold && !mine && confirming && (
          <span role="group" aria-label={`Take over driving ${team}`}>
            Take {team} from {hold.name}?{" "}
            <button type="button" className="btn btn-small" data-testid={`driving-take-cancel-${team}`} onClick={() => setConfirming(false)}>
              Cancel
            </button>{" "}
            <button
              type="button"
              className="btn btn-small btn-danger"
              data-testid={`driving-take-confirm-${team}`}
              onClick={() => {
                setConfirming(false);
                void act("Take over driving", () => takeDriving(team));
              }}
            >
              Take over
            </button>
          </span>
        )}
      </td>
    </tr>
  );
}

/** The Health tab's operators: this page's name, the pages connected, who drives, the
 * latest operator actions. */
export function OperatorsHealth({ h }: { h: Health }) {
  const me = useMe();
  const [name, setName] = useState<string | null>(null);
  const operators = h.operators ?? [];
  const actions = h.operator_actions ?? [];
  return (
    <section data-testid="health-operators-section">
      <h3>
        Operators{" "}
        <span className="muted">
          you are <b data-testid="my-name">{me?.name ?? "…"}</b> ({me?.role ?? "?"} at {me?.address ?? "?"}){" "}
        </span>
        {name === null ? (
          <button type="button" className="btn btn-small" data-testid="name-change" onClick={() => setName(me?.name ?? "")}>
            Change name
          </button>
        ) : (
          <form
            style={{ display: "inline" }}
            onSubmit={(ev) => {
              ev.preventDefault();
              writeName(name.trim() || "local");
              localStorage.setItem(ASKED_KEY, "1");
              setName(null);
              void refreshMe();
            }}
          >
            <input value={name} maxLength={32} data-testid="name-edit" onChange={(ev) => setName(ev.target.value)} autoFocus />{" "}
            <button type="submit" className="btn btn-small">
              Save
            </button>
          </form>
        )}
      </h3>
      <table className="htable" data-testid="health-operators">
        <tbody>
          {operators.map((o) => (
            <tr key={o.session} data-testid="operator-row" data-name={o.name}>
              <td className="hname">{o.name}</td>
              <td>{o.role}</td>
              <td className="num">{o.address}</td>
              <td className="muted">since {clock(o.since_unix)}</td>
            </tr>
          ))}
        </tbody>
      </table>
      <h3>Driving</h3>
      <table className="htable" data-testid="health-driving">
        <tbody>
          {TEAMS.map((t) => (
            <DrivingRow key={t} team={t} hold={(h.driving ?? []).find((d) => d.team === t)} me={me} />
          ))}
        </tbody>
      </table>
      <h3>
        Operator actions <span className="muted">newest first (all are in the session log)</span>
      </h3>
      <ol className="operator-actions" data-testid="operator-actions">
        {actions.length === 0 && <li className="muted">none yet</li>}
        {actions.map((a) => (
          <li key={a.seq} data-testid="operator-action" data-action={a.action}>
            <span className="num muted">{clock(a.time_unix)}</span> <b>{a.action}</b> {a.by}
            {a.details ? <span className="muted"> · {a.details}</span> : null}
          </li>
        ))}
      </ol>
    </section>
  );
}
