import { useEffect, useRef, useState } from "react";
import { commitField } from "../params/paramsStore";
import { formatValue, localError, parseNumberInput, type FieldDesc } from "../params/schema";

/**
 * One parameter: slider + number box (numbers), select (enums), toggle (booleans), text.
 * A change is sent as a PATCH; a refused value shows the server's message and the field
 * returns to the server value. Values pushed by the server replace the shown value unless
 * the user is editing this field, in which case a "changed remotely" marker appears.
 */
export function ParamField({ f, value, compact = false }: { f: FieldDesc; value: unknown; compact?: boolean }) {
  const [draft, setDraft] = useState(() => formatValue(f, value));
  const [error, setError] = useState<string | null>(null);
  const [remote, setRemote] = useState<unknown>(undefined);
  const [flash, setFlash] = useState(false);
  const editing = useRef(false);
  const lastSent = useRef<unknown>(undefined);
  const prevValue = useRef(value);
  const slideTimer = useRef<ReturnType<typeof setTimeout> | null>(null);

  useEffect(() => {
    if (Object.is(prevValue.current, value)) return;
    prevValue.current = value;
    const ours = Object.is(lastSent.current, value);
    if (editing.current && draft !== formatValue(f, value)) {
      if (!ours) setRemote(value);
      return;
    }
    setDraft(formatValue(f, value));
    setRemote(undefined);
    if (!ours) {
      setFlash(true);
      const t = setTimeout(() => setFlash(false), 2500);
      return () => clearTimeout(t);
    }
    return undefined;
  }, [value, f, draft]);

  const send = async (v: unknown) => {
    lastSent.current = v;
    setRemote(undefined);
    const err = await commitField(f, v);
    editing.current = false;
    setError(err);
    if (err) {
      lastSent.current = undefined;
      // Back to what the server holds (nothing was applied).
      setDraft(formatValue(f, prevValue.current));
    }
  };

  const commitText = () => {
    if (f.kind !== "number" && f.kind !== "integer" && f.kind !== "string") return;
    if (draft === formatValue(f, value)) {
      editing.current = false;
      setRemote(undefined);
      return;
    }
    if (lastSent.current !== undefined && formatValue(f, lastSent.current) === draft) return; // in flight
    if (f.kind === "string") {
      void send(draft);
      return;
    }
    const v = parseNumberInput(draft, f.kind);
    if (v === null) {
      setError("not a number");
      setDraft(formatValue(f, value));
      editing.current = false;
      return;
    }
    void send(v);
  };

  const isNum = f.kind === "number" || f.kind === "integer";
  const hasRange = isNum && f.min !== undefined && f.max !== undefined;
  const numeric = isNum ? Number(draft) : Number.NaN;
  const changed = f.default !== undefined && !Object.is(value, f.default);
  const help = [f.description, isNum && f.min !== undefined ? `range ${f.min} … ${f.max ?? "∞"}${f.unit ? ` ${f.unit}` : ""}` : "", f.default !== undefined ? `default ${String(f.default)}` : ""]
    .filter(Boolean)
    .join(" · ");

  return (
    <div
      className={`pfield ${error ? "pfield-error" : ""} ${flash ? "pfield-flash" : ""} ${changed ? "pfield-changed" : ""}`}
      data-testid={`param-${f.id}`}
    >
      <label className="pfield-label" htmlFor={`param-input-${f.id}`} title={help}>
        {f.title}
        {f.unit && <span className="pfield-unit"> [{f.unit}]</span>}
      </label>
      <div className="pfield-control">
        {hasRange && (
          <input
            type="range"
            className="pfield-slider"
            aria-label={`${f.title} slider`}
            data-testid={`param-slider-${f.id}`}
            min={f.min}
            max={f.max}
            step={f.step ?? "any"}
            value={Number.isFinite(numeric) ? numeric : Number(value)}
            onChange={(ev) => {
              const v = Number(ev.target.value);
              setDraft(formatValue(f, v));
              if (slideTimer.current) clearTimeout(slideTimer.current);
              slideTimer.current = setTimeout(() => void send(v), 150);
            }}
          />
        )}
        {isNum || f.kind === "string" ? (
          <input
            id={`param-input-${f.id}`}
            className={`pfield-input ${isNum ? "num" : "pfield-text"}`}
            data-testid={`param-input-${f.id}`}
            type="text"
            inputMode={isNum ? "decimal" : "text"}
            spellCheck={isNum ? undefined : false}
            autoComplete="off"
            value={draft}
            size={isNum ? (compact ? 6 : 8) : compact ? 12 : 24}
            onFocus={() => {
              editing.current = true;
            }}
            onChange={(ev) => {
              editing.current = true;
              setDraft(ev.target.value);
            }}
            onKeyDown={(ev) => {
              if (ev.key === "Enter") commitText();
              if (ev.key === "Escape") {
                setDraft(formatValue(f, value));
                editing.current = false;
                setRemote(undefined);
                (ev.target as HTMLInputElement).blur();
              }
              ev.stopPropagation();
            }}
            onBlur={commitText}
          />
        ) : f.kind === "enum" ? (
          <select
            id={`param-input-${f.id}`}
            data-testid={`param-input-${f.id}`}
            value={String(value ?? "")}
            onChange={(ev) => {
              const opt = f.options?.find((o) => String(o) === ev.target.value);
              void send(opt ?? ev.target.value);
            }}
          >
            {f.options?.map((o) => (
              <option key={String(o)} value={String(o)}>
                {String(o)}
              </option>
            ))}
          </select>
        ) : (
          <label className="toggle">
            <input
              id={`param-input-${f.id}`}
              type="checkbox"
              data-testid={`param-input-${f.id}`}
              checked={value === true}
              onChange={(ev) => void send(ev.target.checked)}
            />
            <span className="toggle-track" aria-hidden="true" />
            <span className="toggle-text">{value === true ? "on" : "off"}</span>
          </label>
        )}
        <button
          type="button"
          className="btn btn-icon"
          title={`Reset to default (${String(f.default)})`}
          aria-label={`Reset ${f.title} to default`}
          data-testid={`param-reset-${f.id}`}
          disabled={!changed}
          onClick={() => void send(f.default)}
        >
          ↺
        </button>
      </div>
      {!compact && f.description && <div className="pfield-help">{f.description}</div>}
      {remote !== undefined && (
        <div className="pfield-remote" data-testid={`param-remote-${f.id}`}>
          changed remotely to <b>{formatValue(f, remote)}</b>{" "}
          <button
            type="button"
            className="linkbtn"
            onClick={() => {
              editing.current = false;
              setDraft(formatValue(f, remote));
              setRemote(undefined);
            }}
          >
            take it
          </button>
        </div>
      )}
      {error && (
        <div className="pfield-msg" role="alert" data-testid={`param-error-${f.id}`}>
          {error}
        </div>
      )}
      {!error && isNum && draft !== formatValue(f, value) && localError(f, parseNumberInput(draft, f.kind)) && (
        <div className="pfield-hint">{localError(f, parseNumberInput(draft, f.kind))} (Enter to send anyway)</div>
      )}
    </div>
  );
}
