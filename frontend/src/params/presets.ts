// Preset and import actions of the parameters panel (the panel calls these; these call the
// transport and hand accepted parameters to the store).

import { ApiError, deletePreset, getPreset, importParams, listPresets, loadPreset, savePreset } from "../api/http";
import type { ParamChange, PresetDetail } from "../api/types";
import { acceptParams } from "./paramsStore";

export type { ParamChange };

/** The server's message for a failed request (its detail), else the error's text. */
export function presetErrorText(e: unknown): string {
  return e instanceof ApiError ? e.message : e instanceof Error ? e.message : String(e);
}

export const presetNames = async (): Promise<string[]> => (await listPresets()).presets;
export const saveCurrentAs = (name: string): Promise<unknown> => savePreset(name);
export const removePreset = (name: string): Promise<unknown> => deletePreset(name);
export const presetDetail = (name: string): Promise<PresetDetail> => getPreset(name);

/** Load a preset: the parameters in force become its values (the store takes the answer). */
export async function applyPreset(name: string): Promise<void> {
  acceptParams(await loadPreset(name));
}

/** Import an exported parameters file's text. */
export async function importParamsText(text: string): Promise<void> {
  acceptParams(await importParams(text));
}
