// Pure CSV (RFC 4180) of plotted data: a time column plus one column per signal.

export function csvCell(v: unknown): string {
  if (v === null || v === undefined) return "";
  if (typeof v === "number") return Number.isFinite(v) ? String(v) : "";
  const s = String(v);
  return /[",\r\n]/.test(s) ? `"${s.replace(/"/g, '""')}"` : s;
}

/**
 * `t` are Unix seconds; the first column is `t_s` relative to `t0` (the window start) unless
 * `absolute`, then `unix_s`.
 */
export function toCsv(
  t: readonly number[],
  names: readonly string[],
  cols: readonly (readonly (number | null)[])[],
  opts: { t0?: number; absolute?: boolean } = {},
): string {
  const t0 = opts.absolute ? 0 : (opts.t0 ?? t[0] ?? 0);
  const lines = [[opts.absolute ? "unix_s" : "t_s", ...names].map(csvCell).join(",")];
  for (let i = 0; i < t.length; i++) {
    const row = [csvCell(Math.round(((t[i] as number) - t0) * 1e6) / 1e6)];
    for (const c of cols) row.push(csvCell(c[i] ?? null));
    lines.push(row.join(","));
  }
  return `${lines.join("\r\n")}\r\n`;
}

/** Start a browser download of `text`. */
export function downloadText(filename: string, text: string, type = "text/csv"): void {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = document.createElement("a");
  a.href = url;
  a.download = filename;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}
