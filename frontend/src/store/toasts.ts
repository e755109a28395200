// Transient notifications (errors from the server, confirmations).

import { useSyncExternalStore } from "react";
import { createStore } from "./createStore";

export type ToastKind = "error" | "info";

export interface Toast {
  id: number;
  kind: ToastKind;
  text: string;
}

const toastStore = createStore<{ toasts: Toast[] }>({ toasts: [] });
let nextId = 1;

export function pushToast(kind: ToastKind, text: string, ttlMs = kind === "error" ? 6000 : 2500): number {
  const id = nextId++;
  toastStore.setState((s) => ({ toasts: [...s.toasts, { id, kind, text }].slice(-4) }));
  setTimeout(() => dismissToast(id), ttlMs);
  return id;
}

export function dismissToast(id: number): void {
  toastStore.setState((s) => {
    const toasts = s.toasts.filter((t) => t.id !== id);
    return toasts.length === s.toasts.length ? {} : { toasts };
  });
}

export function useToasts(): Toast[] {
  return useSyncExternalStore(
    toastStore.subscribe,
    () => toastStore.getState().toasts,
    () => toastStore.getState().toasts,
  );
}

/** The texts shown now (tests). */
export function toastTexts(): string[] {
  return toastStore.getState().toasts.map((t) => t.text);
}
