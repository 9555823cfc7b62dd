/**
 * Which model a plan answer belongs to: its semantic key (the model without
 * the diagram layout, which the planner does not read). The backend's
 * diagnostics of an earlier model are not shown on the current one: after a
 * rename, "no publisher publishes sensor_1.var_1" would otherwise stay on
 * the renamed node until the next answer.
 *
 * @example
 *   planKey({ ...model, layout: { nodes: {} } }) === planKey(model) // true
 */
import type { Diagnostic } from "./diagnostics";
import type { ModdModel } from "./model.gen";

export function planKey(m: ModdModel): string {
  const { layout: _layout, ...rest } = m;
  void _layout;
  return JSON.stringify(rest);
}

const NONE: readonly never[] = []; // one empty list: a stable value for memoised callers

/** The backend's diagnostics when they are for the model of key `current`, else none. */
export function diagnosticsFor<D extends Diagnostic>(diagnostics: readonly D[] | undefined, answeredFor: string | undefined, current: string): readonly D[] {
  if (!diagnostics) return NONE;
  return answeredFor === undefined || answeredFor === current ? diagnostics : NONE;
}
