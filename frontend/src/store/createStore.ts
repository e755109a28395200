// A minimal external store: plain object state, subscribe/getState/setState.
// Hot data (the world at up to 60 Hz) lives here, outside React; the canvas reads it on
// requestAnimationFrame and React components subscribe to slow slices only.

export type Listener = () => void;

export interface Store<T> {
  getState(): T;
  setState(update: Partial<T> | ((s: T) => Partial<T>)): void;
  subscribe(listener: Listener): () => void;
}

export function createStore<T extends object>(initial: T): Store<T> {
  let state = initial;
  const listeners = new Set<Listener>();
  return {
    getState: () => state,
    setState(update) {
      const patch = typeof update === "function" ? update(state) : update;
      let changed = false;
      for (const k of Object.keys(patch) as (keyof T)[]) {
        if (!Object.is(state[k], patch[k])) {
          changed = true;
          break;
        }
      }
      if (!changed) return;
      state = { ...state, ...patch };
      for (const l of [...listeners]) l();
    },
    subscribe(listener) {
      listeners.add(listener);
      return () => {
        listeners.delete(listener);
      };
    },
  };
}
