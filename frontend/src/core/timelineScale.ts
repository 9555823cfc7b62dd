/**
 * A readable schedule strip: tick widths that never overlap however many
 * messages are in view, and time labels at round steps.
 *
 * @example
 *   tickWidth([0, 0.5, 1])     // 10 (the widest, in a 1000-unit strip)
 *   axisTicks(0, 2).map((t) => t.label) // ["0 s", "0.5 s", "1 s", "1.5 s", "2 s"]
 */

/** Width (of a 1000-unit strip) for ticks at positions `xs` (0..1): at most 70 % of the smallest gap, between 1 and 10. */
export function tickWidth(xs: readonly number[], strip = 1000): number {
  const sorted = [...xs].sort((a, b) => a - b);
  let gap = Infinity;
  for (let i = 1; i < sorted.length; i += 1) if (sorted[i] - sorted[i - 1] > 1e-12) gap = Math.min(gap, sorted[i] - sorted[i - 1]);
  if (!Number.isFinite(gap)) return 10;
  return Math.min(10, Math.max(1, 0.7 * gap * strip));
}

/**
 * Ticks at positions `xs` (0..1, in order) laid out so that none overlaps
 * another: a width from the typical gap (70 % of the median, 2 to 10 units of
 * a 1000-unit strip), and ticks closer than that stacked in lanes.
 */
export function layoutTicks(xs: readonly number[], strip = 1000): { width: number; lanes: number; lane: number[] } {
  const gaps = xs.slice(1).map((x, i) => x - xs[i]).filter((g) => g > 1e-12).sort((a, b) => a - b);
  const median = gaps.length ? gaps[gaps.length >> 1] : 1;
  const width = Math.min(10, Math.max(2, 0.7 * median * (strip - 10)));
  const ends: number[] = [];
  const lane = xs.map((x) => {
    const left = x * (strip - width);
    let i = ends.findIndex((end) => end <= left);
    if (i < 0) { i = ends.length; ends.push(0); }
    ends[i] = left + width + 0.5;
    return i;
  });
  return { width, lanes: Math.max(ends.length, 1), lane };
}

/** A round step (1, 2 or 5 × 10^n) giving about `count` labels over `span`. */
export function niceStep(span: number, count = 5): number {
  const raw = span / Math.max(count, 1);
  const p = 10 ** Math.floor(Math.log10(raw));
  return [1, 2, 5, 10].map((m) => m * p).find((s) => s >= raw) ?? 10 * p;
}

/** Labelled times between `from` and `to` (seconds), with their position 0..1. */
export function axisTicks(from: number, to: number, count = 5): Array<{ x: number; label: string }> {
  const span = to - from;
  if (!(span > 0)) return [];
  const step = niceStep(span, count);
  const digits = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
  const out: Array<{ x: number; label: string }> = [];
  for (let t = Math.ceil(from / step - 1e-9) * step; t <= to + 1e-9; t += step) {
    out.push({ x: (t - from) / span, label: `${Number(t.toFixed(digits))} s` });
  }
  return out;
}
