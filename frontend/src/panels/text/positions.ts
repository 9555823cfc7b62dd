/** A diagnostic's located text as offsets `[from, to)`: its start, and its end
 * when the parser gave one (else one character); `to` is never before `from`. */
export function rangeOf(
  text: string,
  d: { line?: number | null; col?: number | null; end_line?: number | null; end_col?: number | null },
): { from: number; to: number } {
  const from = d.line ? offsetOf(text, d.line, d.col ?? 1) : 0;
  const end = d.line && d.end_line ? offsetOf(text, d.end_line, d.end_col ?? 1) : from + 1;
  return { from, to: Math.min(Math.max(end, from + 1), text.length) };
}

/** line:col (1-based, as the parser reports) → offset in a text, clamped. */
export function offsetOf(text: string, line: number, col: number): number {
  let offset = 0;
  for (let l = 1; l < line; l += 1) {
    const next = text.indexOf("\n", offset);
    if (next < 0) return text.length;
    offset = next + 1;
  }
  const end = text.indexOf("\n", offset);
  const lineEnd = end < 0 ? text.length : end;
  return Math.min(offset + Math.max(col - 1, 0), lineEnd);
}
