/** One model change as a line of the history diff: "~ /subscribers/sub_1/periodS: 2.0 → 4.0". */
import type { Change } from "../../core/diff";
import { showValue } from "../../core/merge";

const MAX = 120;
const short = (v: unknown) => { const s = showValue(v); return s.length > MAX ? `${s.slice(0, MAX)}…` : s; };

export function changeLine(c: Change): string {
  if (c.op === "add") return `+ ${c.pointer}: ${short(c.after)}`;
  if (c.op === "remove") return `− ${c.pointer}`;
  return `~ ${c.pointer}: ${short(c.before)} → ${short(c.after)}`;
}
