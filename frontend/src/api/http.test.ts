import { afterEach, describe, expect, it, vi } from "vitest";
import {
  ApiError,
  errorMessageFromBody,
  notifyUnauthorized,
  postTarget,
  request,
  resetUnauthorizedNotice,
  unauthorizedMessage,
} from "./http";
import { toastTexts } from "../store/toasts";

describe("errorMessageFromBody", () => {
  it("reads FastAPI string details", () => {
    expect(errorMessageFromBody(404, { detail: "no geometry packet received yet" })).toBe(
      "no geometry packet received yet",
    );
  });
  it("joins validation errors with their location", () => {
    const body = {
      detail: [
        { loc: ["body", "x"], msg: "point is far outside the field", type: "value_error" },
        { loc: ["path", "id"], msg: "Input should be less than or equal to 15" },
      ],
    };
    expect(errorMessageFromBody(422, body)).toBe(
      "x: point is far outside the field; path.id: Input should be less than or equal to 15",
    );
  });
  it("falls back to text or the status", () => {
    expect(errorMessageFromBody(500, "Internal Server Error")).toBe("Internal Server Error");
    expect(errorMessageFromBody(502, "", "502 Bad Gateway")).toBe("502 Bad Gateway");
    expect(errorMessageFromBody(503, { detail: [] })).toBe("HTTP 503");
  });
});

describe("postTarget", () => {
  afterEach(() => {
    vi.unstubAllGlobals();
  });

  it("posts rounded mm without orientation", async () => {
    const fetchMock = vi.fn(async () => new Response('{"team":"blue","id":3,"target":{"x":1200,"y":-300,"orientation":null}}'));
    vi.stubGlobal("fetch", fetchMock);
    await postTarget("blue", 3, { x: 1200.4, y: -299.6 });
    expect(fetchMock).toHaveBeenCalledTimes(1);
    const [url, init] = fetchMock.mock.calls[0] as unknown as [string, RequestInit];
    expect(url).toBe("/api/robots/blue/3/target");
    expect(init.method).toBe("POST");
    expect(JSON.parse(String(init.body))).toEqual({ x: 1200, y: -300 });
    // the station refuses state changes without JSON or this header (cross-site requests)
    expect(init.headers).toMatchObject({ "Content-Type": "application/json", "X-Touchline": "1" });
  });

  it("sends the station's header on requests without a body", async () => {
    const fetchMock = vi.fn(async () => new Response("{}"));
    vi.stubGlobal("fetch", fetchMock);
    await request("DELETE", "/api/robots/blue/1/target");
    const [, init] = fetchMock.mock.calls[0] as unknown as [string, RequestInit];
    expect(init.headers).toEqual({ "X-Touchline": "1" });
  });

  it("throws an ApiError with the server's message on 422", async () => {
    vi.stubGlobal(
      "fetch",
      vi.fn(async () => new Response(JSON.stringify({ detail: [{ loc: ["body"], msg: "far outside the field" }] }), { status: 422 })),
    );
    const err = await postTarget("yellow", 1, { x: 99999, y: 0 }).catch((e: unknown) => e);
    expect(err).toBeInstanceOf(ApiError);
    expect((err as ApiError).status).toBe(422);
    expect((err as ApiError).message).toBe("far outside the field");
  });
});

describe("a 401 says how to log in", () => {
  afterEach(() => {
    vi.unstubAllGlobals();
    resetUnauthorizedNotice();
  });

  it("toasts the login help once, and the error keeps the station's reason", async () => {
    const detail =
      "this station requires the operator token: open the URL printed at start (http://HOST:PORT/login?token=...), or send Authorization: Bearer <token>";
    vi.stubGlobal("fetch", vi.fn(async () => new Response(JSON.stringify({ detail }), { status: 401 })));
    const err = await postTarget("blue", 1, { x: 0, y: 0 }).catch((e: unknown) => e);
    expect(err).toBeInstanceOf(ApiError);
    expect((err as ApiError).status).toBe(401);
    expect((err as ApiError).message).toBe(detail);
    const shown = toastTexts().filter((t) => t.startsWith("Not logged in"));
    expect(shown).toHaveLength(1);
    expect(shown[0]).toContain("/login?token=");
    await postTarget("blue", 1, { x: 0, y: 0 }).catch(() => {});
    expect(toastTexts().filter((t) => t.startsWith("Not logged in"))).toHaveLength(1); // not repeated
  });

  it("names the viewer token when viewing is refused", () => {
    expect(unauthorizedMessage("this station requires a token to view: ...")).toContain("viewer or operator token");
    expect(unauthorizedMessage("this station requires the operator token")).toContain("operator token to change anything");
  });

  it("shows again after 10 s", () => {
    expect(notifyUnauthorized("x", 0)).toBe(true);
    expect(notifyUnauthorized("x", 5_000)).toBe(false);
    expect(notifyUnauthorized("x", 10_001)).toBe(true);
  });
});
