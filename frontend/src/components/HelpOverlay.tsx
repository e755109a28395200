import { SHORTCUTS } from "../shortcuts";
import { uiStore, useUi } from "../store/uiStore";

export function HelpOverlay() {
  const open = useUi((s) => s.help);
  if (!open) return null;
  return (
    <div className="overlay" role="dialog" aria-modal="true" aria-label="Keyboard shortcuts" data-testid="help-overlay" onClick={() => uiStore.setState({ help: false })}>
      <div className="overlay-box" onClick={(ev) => ev.stopPropagation()}>
        <div className="row">
          <h2>Keyboard and mouse</h2>
          <button type="button" className="btn" onClick={() => uiStore.setState({ help: false })} aria-label="Close help">
            ✕
          </button>
        </div>
        <table className="keys">
          <tbody>
            {SHORTCUTS.map(([k, what]) => (
              <tr key={k}>
                <td>
                  <kbd>{k}</kbd>
                </td>
                <td>{what}</td>
              </tr>
            ))}
          </tbody>
        </table>
      </div>
    </div>
  );
}
