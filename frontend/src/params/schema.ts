// Pure: the pydantic JSON schema of StationParams (GET /api/params/schema) -> a form model.
// Groups are the top-level properties; every leaf becomes a typed field descriptor with its
// path, bounds, unit, step and help text. Nested models inside a group are flattened with a
// longer path (e.g. ["control", "limits", "max_speed_mps"]), so nothing here is written per
// parameter: a new backend parameter appears in the UI by itself.

export type JsonSchema = { [key: string]: unknown };

export type FieldKind = "number" | "integer" | "boolean" | "enum" | "string";

export interface FieldDesc {
  /** Path from the root of the values, e.g. ["goto", "kp_per_s"]. */
  path: string[];
  /** The path joined with dots: "goto.kp_per_s" (also the key of 422 errors). */
  id: string;
  /** The group (top-level property) this field belongs to. */
  group: string;
  /** Section inside the group for nested models ("" for direct fields), e.g. "limits". */
  section: string;
  key: string;
  title: string;
  description: string;
  kind: FieldKind;
  default: unknown;
  min?: number;
  max?: number;
  /** Strict bounds (exclusiveMinimum / exclusiveMaximum). */
  exclusiveMin?: boolean;
  exclusiveMax?: boolean;
  step?: number;
  unit: string;
  options?: (string | number)[];
  /** Field allows null (pydantic `X | None`). */
  nullable: boolean;
}

export interface GroupDesc {
  key: string;
  title: string;
  description: string;
  fields: FieldDesc[];
}

function isObj(v: unknown): v is JsonSchema {
  return typeof v === "object" && v !== null && !Array.isArray(v);
}

function str(v: unknown): string {
  return typeof v === "string" ? v : "";
}

function num(v: unknown): number | undefined {
  return typeof v === "number" && Number.isFinite(v) ? v : undefined;
}

/** Resolve a local "#/$defs/Name" (or "#/definitions/Name") reference; unknown refs -> {}. */
export function resolveRef(root: JsonSchema, node: JsonSchema): JsonSchema {
  let cur = node;
  for (let i = 0; i < 16 && typeof cur.$ref === "string"; i++) {
    const ref = cur.$ref as string;
    if (!ref.startsWith("#/")) return {};
    let target: unknown = root;
    for (const part of ref.slice(2).split("/")) {
      target = isObj(target) ? target[part.replace(/~1/g, "/").replace(/~0/g, "~")] : undefined;
    }
    if (!isObj(target)) return {};
    // Keys next to $ref (description, default) override the referenced schema's.
    const { $ref: _ignored, ...rest } = cur;
    cur = { ...target, ...rest };
  }
  return cur;
}

/** `anyOf: [X, {type: null}]` -> X with nullable; `allOf: [ref]` -> ref. */
function unwrap(root: JsonSchema, node: JsonSchema): { schema: JsonSchema; nullable: boolean } {
  let s = resolveRef(root, node);
  let nullable = false;
  for (const k of ["anyOf", "oneOf"] as const) {
    const alts = s[k];
    if (Array.isArray(alts)) {
      const nonNull = alts.filter((a) => !(isObj(a) && a.type === "null"));
      nullable = nonNull.length < alts.length;
      if (nonNull.length >= 1 && isObj(nonNull[0])) {
        const { [k]: _drop, ...rest } = s;
        s = { ...resolveRef(root, nonNull[0] as JsonSchema), ...rest };
      }
    }
  }
  if (Array.isArray(s.allOf) && s.allOf.length === 1 && isObj(s.allOf[0])) {
    const { allOf: _drop, ...rest } = s;
    s = { ...resolveRef(root, s.allOf[0] as JsonSchema), ...rest };
  }
  if (Array.isArray(s.type)) {
    const types = (s.type as unknown[]).filter((t) => t !== "null");
    nullable = nullable || types.length < (s.type as unknown[]).length;
    s = { ...s, type: types[0] };
  }
  return { schema: s, nullable };
}

/** "max_speed_mps" -> "Max speed mps" when the schema has no title. */
export function humanize(key: string): string {
  const s = key.replace(/_/g, " ").trim();
  return s.charAt(0).toUpperCase() + s.slice(1);
}

function leaf(root: JsonSchema, path: string[], group: string, section: string, node: JsonSchema): FieldDesc | null {
  const { schema: s, nullable } = unwrap(root, node);
  const key = path[path.length - 1] ?? "";
  let kind: FieldKind;
  let options: (string | number)[] | undefined;
  if (Array.isArray(s.enum)) {
    kind = "enum";
    options = (s.enum as unknown[]).filter((o): o is string | number => typeof o === "string" || typeof o === "number");
  } else if (s.const !== undefined && (typeof s.const === "string" || typeof s.const === "number")) {
    kind = "enum";
    options = [s.const];
  } else if (s.type === "boolean") kind = "boolean";
  else if (s.type === "integer") kind = "integer";
  else if (s.type === "number") kind = "number";
  else if (s.type === "string") kind = "string";
  else return null;
  const desc: FieldDesc = {
    path,
    id: path.join("."),
    group,
    section,
    key,
    title: humanize(key),
    description: str(s.description),
    kind,
    default: s.default,
    unit: str(s.unit),
    nullable,
  };
  const min = num(s.minimum) ?? num(s.exclusiveMinimum);
  const max = num(s.maximum) ?? num(s.exclusiveMaximum);
  if (min !== undefined) desc.min = min;
  if (max !== undefined) desc.max = max;
  if (num(s.exclusiveMinimum) !== undefined) desc.exclusiveMin = true;
  if (num(s.exclusiveMaximum) !== undefined) desc.exclusiveMax = true;
  const step = num(s.step) ?? num(s.multipleOf);
  if (step !== undefined && step > 0) desc.step = step;
  else if (kind === "integer") desc.step = 1;
  if (options) desc.options = options;
  return desc;
}

function collect(root: JsonSchema, node: JsonSchema, path: string[], group: string, out: FieldDesc[], depth: number): void {
  const { schema: s } = unwrap(root, node);
  const props = s.properties;
  if (!isObj(props) || depth > 8) return;
  for (const [key, child] of Object.entries(props)) {
    if (!isObj(child)) continue;
    const childPath = [...path, key];
    const { schema: cs } = unwrap(root, child);
    if (isObj(cs.properties)) {
      collect(root, child, childPath, group, out, depth + 1);
    } else {
      const f = leaf(root, childPath, group, childPath.slice(1, -1).join("."), child);
      if (f) out.push(f);
    }
  }
}

/** The form model of a parameters schema: one group per top-level property. */
export function schemaToForm(schema: unknown): GroupDesc[] {
  if (!isObj(schema)) return [];
  const root = schema;
  const { schema: top } = unwrap(root, root);
  const props = top.properties;
  if (!isObj(props)) return [];
  const groups: GroupDesc[] = [];
  for (const [key, node] of Object.entries(props)) {
    if (!isObj(node)) continue;
    const { schema: gs } = unwrap(root, node);
    const fields: FieldDesc[] = [];
    if (isObj(gs.properties)) collect(root, node, [key], key, fields, 1);
    else {
      const f = leaf(root, [key], key, "", node);
      if (f) fields.push(f);
    }
    // The description next to the $ref names the group; the model's docstring explains it.
    const refDesc = str(node.description);
    const model = typeof node.$ref === "string" ? resolveRef(root, { $ref: node.$ref }) : gs;
    const modelDesc = str(model.description);
    groups.push({
      key,
      title: refDesc || str(gs.title) || humanize(key),
      description: modelDesc !== refDesc ? modelDesc : "",
      fields,
    });
  }
  return groups;
}

/** Value at a path in a nested values object (undefined when missing). */
export function getAt(values: unknown, path: readonly string[]): unknown {
  let cur = values;
  for (const p of path) {
    if (!isObj(cur)) return undefined;
    cur = cur[p];
  }
  return cur;
}

/** The partial nested object of a PATCH that sets one leaf: ["a","b"], 1 -> {a: {b: 1}}. */
export function patchFor(path: readonly string[], value: unknown): JsonSchema {
  let out: unknown = value;
  for (let i = path.length - 1; i >= 0; i--) out = { [path[i] as string]: out };
  return out as JsonSchema;
}

/** Merge several leaf patches into one nested object. */
export function mergePatches(...patches: JsonSchema[]): JsonSchema {
  const out: JsonSchema = {};
  const merge = (dst: JsonSchema, src: JsonSchema) => {
    for (const [k, v] of Object.entries(src)) {
      if (isObj(v) && isObj(dst[k])) merge(dst[k] as JsonSchema, v);
      else if (isObj(v)) {
        dst[k] = {};
        merge(dst[k] as JsonSchema, v);
      } else dst[k] = v;
    }
  };
  for (const p of patches) merge(out, p);
  return out;
}

/** A PATCH resetting every field of a group to its default. */
export function groupResetPatch(group: GroupDesc): JsonSchema {
  return mergePatches(...group.fields.filter((f) => f.default !== undefined).map((f) => patchFor(f.path, f.default)));
}

/**
 * Field errors of a 422 body `{"detail": [{"loc": ["body", group, field], "msg"}]}` keyed by
 * field id ("group.field"); errors that name no field go under "".
 */
export function errorsByField(body: unknown): Record<string, string> {
  const out: Record<string, string> = {};
  const detail = isObj(body) ? body.detail : undefined;
  if (typeof detail === "string") {
    out[""] = detail;
    return out;
  }
  if (!Array.isArray(detail)) return out;
  for (const d of detail) {
    if (!isObj(d)) continue;
    const loc = Array.isArray(d.loc) ? d.loc.map(String) : [];
    const path = loc[0] === "body" ? loc.slice(1) : loc;
    const id = path.join(".");
    const msg = str(d.msg) || "invalid value";
    out[id] = out[id] ? `${out[id]}; ${msg}` : msg;
  }
  return out;
}

/** The error of a field: its own, or one of a parent path (e.g. a whole group refused). */
export function errorForField(errors: Record<string, string>, f: FieldDesc): string | undefined {
  if (errors[f.id]) return errors[f.id];
  for (const [id, msg] of Object.entries(errors)) {
    if (id && f.id.startsWith(`${id}.`)) return msg;
    // pydantic reports union/extra errors under a longer loc (e.g. field + type name).
    if (id.startsWith(`${f.id}.`)) return msg;
  }
  return undefined;
}

/**
 * Parse what the user typed into a number box. Returns the number (not clamped: the server
 * validates and explains) or null when it is not a number at all. Commas are decimal points.
 */
export function parseNumberInput(text: string, kind: FieldKind): number | null {
  const t = text.trim().replace(",", ".");
  if (t === "") return null;
  if (/^[+-]?(nan|inf(inity)?)$/i.test(t)) return /^[+-]?nan$/i.test(t) ? Number.NaN : t.startsWith("-") ? -Infinity : Infinity;
  if (!/^[+-]?(\d+\.?\d*|\.\d+)(e[+-]?\d+)?$/i.test(t)) return null;
  const v = Number(t);
  if (kind === "integer" && Number.isInteger(v) === false) return v; // the server says why
  return v;
}

/** Client-side check mirroring the schema, for immediate feedback before the server answers. */
export function localError(f: FieldDesc, v: unknown): string | null {
  if (f.kind === "number" || f.kind === "integer") {
    if (typeof v !== "number" || !Number.isFinite(v)) return "must be a finite number";
    if (f.min !== undefined && (f.exclusiveMin ? v <= f.min : v < f.min)) return `must be ${f.exclusiveMin ? ">" : ">="} ${f.min}`;
    if (f.max !== undefined && (f.exclusiveMax ? v >= f.max : v > f.max)) return `must be ${f.exclusiveMax ? "<" : "<="} ${f.max}`;
    if (f.kind === "integer" && !Number.isInteger(v)) return "must be a whole number";
  }
  if (f.kind === "enum" && f.options && !f.options.includes(v as string | number)) return `must be one of ${f.options.join(", ")}`;
  return null;
}

/** Decimal places to show for a field's step (0.05 -> 2, 1 -> 0). */
export function decimalsFor(f: FieldDesc): number {
  if (f.kind === "integer") return 0;
  const step = f.step ?? 0.01;
  const s = String(step);
  if (s.includes("e-")) return Number(s.split("e-")[1]);
  const dot = s.indexOf(".");
  return dot < 0 ? 0 : Math.min(6, s.length - dot - 1);
}

/** A value as shown in a number box. */
export function formatValue(f: FieldDesc, v: unknown): string {
  if (typeof v === "number") {
    if (!Number.isFinite(v)) return String(v);
    const d = decimalsFor(f);
    // Never hide precision the server holds (e.g. a value imported with more digits).
    const fixed = v.toFixed(d);
    return Number(fixed) === v ? fixed : String(v);
  }
  if (v === null || v === undefined) return "";
  return String(v);
}

/** Fields whose value differs from the default. */
export function changedFields(groups: readonly GroupDesc[], values: unknown): FieldDesc[] {
  const out: FieldDesc[] = [];
  for (const g of groups) for (const f of g.fields) if (f.default !== undefined && getAt(values, f.path) !== f.default) out.push(f);
  return out;
}

/** Enum fields that choose a filter or a controller (shown in the robot panel). */
export function chooserFields(groups: readonly GroupDesc[]): FieldDesc[] {
  const out: FieldDesc[] = [];
  for (const g of groups)
    for (const f of g.fields)
      if (f.kind === "enum" && /filter|algorithm|controller/i.test(f.id)) out.push(f);
  return out;
}
