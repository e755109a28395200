import { useEffect, useRef, useState } from "react";
import { commitPatch, ensureSchema, useParamForm } from "../params/paramsStore";
import {
  applyPreset,
  importParamsText,
  presetDetail,
  presetErrorText,
  presetNames,
  removePreset,
  saveCurrentAs,
  type ParamChange,
} from "../params/presets";
import { changedFields, getAt, groupResetPatch, type GroupDesc } from "../params/schema";
import { useAppState } from "../store/hooks";
import { pushToast } from "../store/toasts";
import { ParamField } from "./ParamField";
import { StationFolders } from "./StationFolders";

const errText = presetErrorText;

function Group({ g, values, open }: { g: GroupDesc; values: unknown; open: boolean }) {
  const changed = changedFields([g], values).length;
  let section = "";
  return (
    <details className="pgroup" open={open} data-testid={`param-group-${g.key}`}>
      <summary>
        <span className="pgroup-title">{g.title}</span>
        {changed > 0 && <span className="badge" title="fields not at their default">{changed} changed</span>}
        <button
          type="button"
          className="btn btn-small"
          disabled={changed === 0}
          data-testid={`param-group-reset-${g.key}`}
          title="Reset every field of this group to its default"
          onClick={(ev) => {
            ev.preventDefault();
            void commitPatch(groupResetPatch(g)).then((err) => err && pushToast("error", `Reset ${g.title}: ${err}`));
          }}
        >
          Reset group
        </button>
      </summary>
      {g.description && <p className="pgroup-desc">{g.description}</p>}
      {g.fields.map((f) => {
        const head = f.section !== section ? f.section : null;
        section = f.section;
        return (
          <div key={f.id}>
            {head && <div className="psection">{head}</div>}
            <ParamField f={f} value={getAt(values, f.path)} />
          </div>
        );
      })}
    </details>
  );
}

function DiffTable({ rows, fromLabel, toLabel }: { rows: ParamChange[]; fromLabel: string; toLabel: string }) {
  if (rows.length === 0) return <p className="muted">No differences.</p>;
  return (
    <table className="difftable" data-testid="preset-diff">
      <thead>
        <tr>
          <th>parameter</th>
          <th>{fromLabel}</th>
          <th>{toLabel}</th>
        </tr>
      </thead>
      <tbody>
        {rows.map((r) => (
          <tr key={r.path}>
            <td>{r.path}</td>
            <td className="num">{JSON.stringify(r.from)}</td>
            <td className="num">{JSON.stringify(r.to)}</td>
          </tr>
        ))}
      </tbody>
    </table>
  );
}

function Presets() {
  const [presets, setPresets] = useState<string[]>([]);
  const [name, setName] = useState("");
  const [diff, setDiff] = useState<{ name: string; rows: ParamChange[]; against: "defaults" | "current" } | null>(null);
  const [msg, setMsg] = useState<string | null>(null);
  const fileRef = useRef<HTMLInputElement>(null);
  const version = useAppState((s) => s.params?.version ?? -1);

  const refresh = () =>
    presetNames()
      .then(setPresets)
      .catch((e) => setMsg(errText(e)));
  useEffect(() => {
    void refresh();
  }, [version]);

  const run = async (what: string, fn: () => Promise<unknown>) => {
    try {
      await fn();
      setMsg(null);
      pushToast("info", what);
      void refresh();
    } catch (e) {
      setMsg(errText(e));
    }
  };

  const showDiff = async (p: string, against: "defaults" | "current") => {
    try {
      const r = await presetDetail(p);
      setDiff({ name: p, rows: against === "defaults" ? r.diff_from_defaults : r.diff_from_current, against });
    } catch (e) {
      setMsg(errText(e));
    }
  };

  return (
    <section className="presets" data-testid="presets">
      <h3>Presets</h3>
      <form
        className="row"
        onSubmit={(ev) => {
          ev.preventDefault();
          const n = name.trim();
          if (n) void run(`Saved preset ${n}`, () => saveCurrentAs(n)).then(() => setName(""));
        }}
      >
        <input
          className="text"
          placeholder="save current as…"
          value={name}
          data-testid="preset-name"
          onChange={(ev) => setName(ev.target.value)}
          onKeyDown={(ev) => ev.stopPropagation()}
        />
        <button type="submit" className="btn btn-small" disabled={!name.trim()} data-testid="preset-save">
          Save
        </button>
      </form>
      {msg && (
        <div className="pfield-msg" role="alert">
          {msg}
        </div>
      )}
      <ul className="preset-list">
        {presets.length === 0 && <li className="muted">No presets saved.</li>}
        {presets.map((p) => (
          <li key={p} data-testid={`preset-${p}`}>
            <span className="preset-name">{p}</span>
            <button type="button" className="btn btn-small" onClick={() => void run(`Loaded preset ${p}`, () => applyPreset(p))}>
              Load
            </button>
            <button type="button" className="btn btn-small" onClick={() => void showDiff(p, "defaults")} title="Differences from the defaults">
              Diff
            </button>
            <button type="button" className="btn btn-small" onClick={() => void showDiff(p, "current")} title="What loading it would change">
              vs now
            </button>
            <button type="button" className="btn btn-small btn-danger" onClick={() => void run(`Deleted preset ${p}`, () => removePreset(p))}>
              Delete
            </button>
          </li>
        ))}
      </ul>
      {diff && (
        <div className="diffbox">
          <div className="row">
            <b>
              {diff.name}: {diff.against === "defaults" ? "differences from the defaults" : "what loading it changes"}
            </b>
            <button type="button" className="btn btn-small" onClick={() => setDiff(null)}>
              ✕
            </button>
          </div>
          <DiffTable rows={diff.rows} fromLabel={diff.against === "defaults" ? "default" : "now"} toLabel="preset" />
        </div>
      )}
      <div className="row">
        <a className="btn btn-small" href="/api/params/export" download="touchline-params.json" data-testid="params-export">
          Export…
        </a>
        <button type="button" className="btn btn-small" onClick={() => fileRef.current?.click()} data-testid="params-import">
          Import…
        </button>
        <input
          ref={fileRef}
          type="file"
          accept="application/json,.json"
          hidden
          data-testid="params-import-file"
          onChange={(ev) => {
            const file = ev.target.files?.[0];
            ev.target.value = "";
            if (file) void file.text().then((text) => run(`Imported ${file.name}`, () => importParamsText(text)));
          }}
        />
      </div>
    </section>
  );
}

function CurrentDiff({ groups, values }: { groups: GroupDesc[]; values: unknown }) {
  const changed = changedFields(groups, values);
  if (changed.length === 0) return <p className="muted" data-testid="params-diff">All parameters at their defaults.</p>;
  return (
    <details className="pgroup" data-testid="params-diff">
      <summary>
        <span className="pgroup-title">{changed.length} changed from the defaults</span>
      </summary>
      <DiffTable rows={changed.map((f) => ({ path: f.id, from: f.default, to: getAt(values, f.path) }))} fromLabel="default" toLabel="now" />
    </details>
  );
}

export function ParamsPanel() {
  const form = useParamForm();
  const params = useAppState((s) => s.params);
  const connected = useAppState((s) => s.connection.status === "connected");
  const [filter, setFilter] = useState("");
  useEffect(() => {
    if (connected) void ensureSchema(form.error !== null);
  }, [connected, form.error]);

  if (!form.groups) {
    return <p className="muted">{form.error ? `Cannot load the parameter schema: ${form.error}` : "Loading parameters…"}</p>;
  }
  if (!params) return <p className="muted">Waiting for parameter values…</p>;
  const q = filter.trim().toLowerCase();
  const groups = q
    ? form.groups
        .map((g) => ({ ...g, fields: g.fields.filter((f) => `${f.id} ${f.title} ${f.description}`.toLowerCase().includes(q)) }))
        .filter((g) => g.fields.length > 0)
    : form.groups;
  return (
    <div className="params" data-testid="params-panel" data-version={params.version}>
      <div className="row">
        <input
          className="text grow"
          type="search"
          placeholder="Filter parameters…"
          value={filter}
          onChange={(ev) => setFilter(ev.target.value)}
          onKeyDown={(ev) => ev.stopPropagation()}
          aria-label="Filter parameters"
          data-testid="params-filter"
        />
        <span className="muted num" title="Server parameter version">
          v{params.version}
        </span>
      </div>
      <CurrentDiff groups={form.groups} values={params.values} />
      {groups.map((g, i) => (
        <Group key={g.key} g={g} values={params.values} open={q !== "" || i < 2} />
      ))}
      <Presets />
      <StationFolders />
    </div>
  );
}
