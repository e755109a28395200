// The parameters form model (from the schema, fetched once per backend session) and the
// actions that change parameters on the server. Values themselves live in the app store
// (`params`, from the websocket snapshot and the pushed `params` messages).

import { useSyncExternalStore } from "react";
import { ApiError, getParamsSchema, patchParams, type ParamsReply } from "../api/http";
import { appStore } from "../store/appStore";
import { createStore } from "../store/createStore";
import { errorForField, errorsByField, patchFor, schemaToForm, type FieldDesc, type GroupDesc } from "./schema";

interface FormState {
  groups: GroupDesc[] | null;
  error: string | null;
  loading: boolean;
}

export const formStore = createStore<FormState>({ groups: null, error: null, loading: false });

/** Fetch the schema if it is not loaded yet (or `force`, e.g. after a reconnect). */
export async function ensureSchema(force = false): Promise<void> {
  const s = formStore.getState();
  if (s.loading || (s.groups && !force)) return;
  formStore.setState({ loading: true });
  try {
    const schema = await getParamsSchema();
    formStore.setState({ groups: schemaToForm(schema), error: null, loading: false });
  } catch (e) {
    formStore.setState({ error: (e as Error).message, loading: false });
  }
}

export function useParamForm(): FormState {
  return useSyncExternalStore(formStore.subscribe, formStore.getState, formStore.getState);
}

/** Take a reply of the server (newer version wins over what the websocket brought). */
export function acceptParams(reply: ParamsReply): void {
  appStore.setState((s) => (s.params && s.params.version >= reply.version ? {} : { params: reply }));
}

/** PATCH one field. Resolves to null on success or the server's message for this field. */
export async function commitField(f: FieldDesc, value: unknown): Promise<string | null> {
  return commitPatch(patchFor(f.path, value), f);
}

export async function commitPatch(patch: Record<string, unknown>, f?: FieldDesc): Promise<string | null> {
  try {
    // the version the page shows: a value someone changed since is refused (409), saying the
    // value now (which the websocket has brought to the form)
    acceptParams(await patchParams(patch, appStore.getState().params?.version));
    return null;
  } catch (e) {
    if (e instanceof ApiError && (e.status === 422 || e.status === 409)) {
      const errs = errorsByField(e.body);
      return (f && errorForField(errs, f)) || e.message;
    }
    return e instanceof Error ? e.message : String(e);
  }
}
