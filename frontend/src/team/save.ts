// Pure: what a refused save of a team file means for the editor.
//   409 -> a conflict: the file changed on disk since the edit began (keep the edits, offer
//          "reload from disk" or "overwrite");
//   401 / 403 -> editing is not allowed from this browser: the editor turns read-only and
//          shows the station's reason;
//   anything else (413 too large, 422 a bad name, the station unreachable) -> an error shown
//          beside the Save button, the edits kept.

import { ApiError } from "../api/http";

export type SaveOutcome =
  | { kind: "conflict"; message: string }
  | { kind: "denied"; message: string }
  | { kind: "error"; message: string };

export function saveOutcome(e: unknown): SaveOutcome {
  const text = e instanceof Error ? e.message : String(e);
  if (e instanceof ApiError) {
    if (e.status === 409) return { kind: "conflict", message: text };
    if (e.status === 403 || e.status === 401) return { kind: "denied", message: text };
  }
  return { kind: "error", message: text };
}
