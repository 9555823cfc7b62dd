/**
 * One model change as a line of the history diff, in the model's words
 * (core/changeWords.ts), marked + added, − removed, ~ changed:
 * "~ subscriber sub_1: period 2.0 s → 4.0 s".
 */
import type { Change } from "../../core/diff";
import type { ModdModel } from "../../core/model.gen";
import { sentence } from "../../core/changeWords";

const MAX = 160;
const MARK: Record<Change["op"], string> = { add: "+", remove: "−", replace: "~" };

/** `models`: where topics take their units from (the newer revision first). */
export function changeLine(c: Change, models: ReadonlyArray<ModdModel | undefined> = []): string {
  const text = sentence(c, models).text;
  return `${MARK[c.op]} ${text.length > MAX ? `${text.slice(0, MAX)}…` : text}`;
}
