import { act } from "react";
import { createRoot, type Root } from "react-dom/client";
import { afterEach, beforeEach, vi } from "vitest";

export interface TestDom {
  readonly host: HTMLDivElement;
  readonly root: Root;
  /** The element with this data-testid in the host, if any. */
  q(id: string): Element | null;
}

/**
 * A fresh host element and React root for every test of the file (after `reset`, e.g. store
 * resets), unmounted and removed after it, with stubbed globals restored. Call once at the
 * top of a test file.
 */
export function domPerTest(reset?: () => void): TestDom {
  let host: HTMLDivElement | null = null;
  let root: Root | null = null;
  beforeEach(() => {
    reset?.();
    host = document.createElement("div");
    document.body.appendChild(host);
    root = createRoot(host);
  });
  afterEach(() => {
    const r = root;
    if (r) act(() => r.unmount());
    host?.remove();
    host = root = null;
    vi.unstubAllGlobals();
  });
  return {
    get host() {
      if (!host) throw new Error("no test DOM outside a test");
      return host;
    },
    get root() {
      if (!root) throw new Error("no test DOM outside a test");
      return root;
    },
    q: (id) => host?.querySelector(`[data-testid="${id}"]`) ?? null,
  };
}
