/**
 * Keeps the live plan in step with the edited model: after `delayMs` without
 * edits, posts the model to the backend's planner (aborting a request still
 * running) and stores the plan and its diagnostics. Layout-only edits do not
 * re-plan. Keeps the last valid plan and the one before it (nextPlanState).
 * A calibration chosen in the Plan panel (`plan.calibrate`) re-plans too.
 */
import { useEffect, useRef } from "react";
import type { ModdModel } from "../core/model.gen";
import { useEditor, useEditorStore, useModel } from "../editor/useEditor";
import type { PlanState } from "../editor/store";
import type { PlanResult } from "../api/types";
import { useServices } from "./services";
import { planKey } from "../core/planKey";

/** The plan state after an answer: a valid plan becomes the last valid one, the one before it `previous`. */
export function nextPlanState(prev: PlanState, result: PlanResult): PlanState {
  if (!result.plan) return { ...prev, busy: false, result, error: null };
  return { busy: false, result, error: null, lastValid: result.plan, previous: prev.lastValid ?? null, calibrate: prev.calibrate };
}

/**
 * Edits closer together than this are planned once. Planning takes 5–10 ms on the
 * backend (docs/benchmarks.md): the wait is what the user sees, so it is short;
 * a request still running when the next edit comes is aborted.
 */
export const LIVE_PLAN_DEBOUNCE_MS = 120;

export function useLivePlan(delayMs = LIVE_PLAN_DEBOUNCE_MS): void {
  const { api } = useServices();
  const store = useEditorStore();
  const model = useModel();
  const key = planKey(model);
  const calibrate = useEditor((s) => s.plan.calibrate) ?? null;
  const last = useRef<string | null>(null);

  useEffect(() => {
    const asked = `${calibrate ?? ""}\n${key}`;
    if (asked === last.current) return;
    const ctl = new AbortController();
    const timer = window.setTimeout(async () => {
      store.patch((s) => ({ plan: { ...s.plan, busy: true } }));
      try {
        const result = await api.plan({ model: JSON.parse(key) as ModdModel }, ctl.signal, calibrate ?? undefined);
        last.current = asked;
        store.patch((s) => ({ plan: { ...nextPlanState(s.plan, result), modelKey: key } }));
      } catch (e) {
        if ((e as Error).name === "AbortError") return;
        store.patch((s) => ({ plan: { ...s.plan, busy: false, error: (e as Error).message } }));
      }
    }, delayMs);
    return () => { window.clearTimeout(timer); ctl.abort(); };
  }, [key, calibrate, api, store, delayMs]);
}
