// HTTP calls to the backend (docs/api.md, "HTTP"). Errors carry the server's message.

import type { Team } from "./types";

export class ApiError extends Error {
  readonly status: number;
  constructor(status: number, message: string) {
    super(message);
    this.name = "ApiError";
    this.status = status;
  }
}

/**
 * Human-readable message from a FastAPI error body: `{"detail": "text"}` or
 * `{"detail": [{"loc": [...], "msg": "..."}]}`.
 */
export function errorMessageFromBody(status: number, body: unknown, fallback = ""): string {
  if (typeof body === "object" && body !== null && "detail" in body) {
    const detail = (body as { detail: unknown }).detail;
    if (typeof detail === "string" && detail) return detail;
    if (Array.isArray(detail)) {
      const parts = detail
        .map((d) => {
          if (typeof d !== "object" || d === null) return typeof d === "string" ? d : "";
          const msg = typeof (d as { msg?: unknown }).msg === "string" ? (d as { msg: string }).msg : "";
          const loc = (d as { loc?: unknown }).loc;
          const where = Array.isArray(loc)
            ? loc.filter((p) => p !== "body").map(String).join(".")
            : "";
          return where && msg ? `${where}: ${msg}` : msg;
        })
        .filter(Boolean);
      if (parts.length > 0) return parts.join("; ");
    }
  }
  if (typeof body === "string" && body.trim()) return body.trim().slice(0, 300);
  return fallback || `HTTP ${status}`;
}

async function request<T>(method: string, path: string, body?: unknown): Promise<T> {
  let res: Response;
  try {
    res = await fetch(path, {
      method,
      headers: body === undefined ? {} : { "Content-Type": "application/json" },
      body: body === undefined ? undefined : JSON.stringify(body),
    });
  } catch (e) {
    throw new ApiError(0, `cannot reach the station: ${(e as Error).message}`);
  }
  const text = await res.text();
  let parsed: unknown = text;
  if (text) {
    try {
      parsed = JSON.parse(text);
    } catch {
      /* keep text */
    }
  }
  if (!res.ok) {
    throw new ApiError(res.status, errorMessageFromBody(res.status, parsed, `${res.status} ${res.statusText}`));
  }
  return parsed as T;
}

export interface TargetReply {
  team: Team;
  id: number;
  target: { x: number; y: number; orientation: number | null };
}

export function postTarget(
  team: Team,
  id: number,
  target: { x: number; y: number; orientation?: number },
): Promise<TargetReply> {
  const body: { x: number; y: number; orientation?: number } = {
    x: Math.round(target.x),
    y: Math.round(target.y),
  };
  if (target.orientation !== undefined) body.orientation = target.orientation;
  return request<TargetReply>("POST", `/api/robots/${team}/${id}/target`, body);
}

export function deleteTarget(team: Team, id: number): Promise<unknown> {
  return request<unknown>("DELETE", `/api/robots/${team}/${id}/target`);
}

export function postEstop(active: boolean): Promise<{ estop: boolean }> {
  return request<{ estop: boolean }>("POST", "/api/estop", { active });
}
