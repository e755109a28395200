import { useEffect, useState } from "react";
import { getFolders } from "../api/http";
import type { StationFolder } from "../api/types";
import { presetErrorText } from "../params/presets";
import { useAppState } from "../store/hooks";

/**
 * The folders the station reads code from or writes to (GET /api/folders), read-only: they
 * are set when the station starts (a flag or a TOUCHLINE_* variable), never from the page
 * (docs/security.md). Rows come from the answer, so a folder the backend adds shows by itself.
 */
export function StationFolders({ folders }: { folders?: StationFolder[] }) {
  const [loaded, setLoaded] = useState<StationFolder[] | null>(null);
  const [error, setError] = useState<string | null>(null);
  const connected = useAppState((s) => s.connection.status === "connected");
  useEffect(() => {
    if (folders || !connected) return;
    let live = true;
    getFolders()
      .then((r) => live && (setLoaded(r.folders), setError(null)))
      .catch((e) => live && setError(presetErrorText(e)));
    return () => {
      live = false;
    };
  }, [folders, connected]);
  const rows = folders ?? loaded;
  return (
    <section className="folders" data-testid="station-folders">
      <h3>Station folders</h3>
      <p className="muted">Set when the station starts (command line or environment); not changeable from the page.</p>
      {error && (
        <div className="pfield-msg" role="alert">
          {error}
        </div>
      )}
      {rows === null ? (
        !error && <p className="muted">Loading…</p>
      ) : (
        <table className="difftable">
          <tbody>
            {rows.map((f) => (
              <tr key={f.name} data-testid={`station-folder-${f.name}`} title={`${f.what}. Set with ${f.flag} or ${f.env}.`}>
                <th scope="row">{f.label}</th>
                <td className="folder-paths" data-testid="station-folder-paths">
                  {f.paths.length === 0 ? <span className="muted">none</span> : f.paths.map((p) => <div key={p}>{p}</div>)}
                </td>
                <td className="muted folder-flag">
                  <code>{f.flag}</code>
                </td>
              </tr>
            ))}
          </tbody>
        </table>
      )}
    </section>
  );
}
