/**
 * Undo/redo history of immutable values.
 *
 * Contract: `push` records a new present and clears the redo stack. Pushes that
 * carry the same non-empty `coalesce` key as the previous push replace it
 * instead of stacking (typing in one field is one undo step). The past is
 * bounded by `limit`; the oldest entries are dropped.
 *
 * @example
 *   let h = createHistory(0);
 *   h = push(h, 1); h = undo(h); // h.present === 0
 */
export interface History<T> {
  readonly past: readonly T[];
  readonly present: T;
  readonly future: readonly T[];
  /** Coalescing key of the last push, cleared by undo/redo. */
  readonly lastKey: string | null;
  readonly limit: number;
}

export function createHistory<T>(present: T, limit = 200): History<T> {
  return { past: [], present, future: [], lastKey: null, limit };
}

export function push<T>(h: History<T>, next: T, coalesce?: string): History<T> {
  if (next === h.present) return h;
  if (coalesce && coalesce === h.lastKey) {
    return { ...h, present: next, future: [] };
  }
  const past = [...h.past, h.present];
  if (past.length > h.limit) past.splice(0, past.length - h.limit);
  return { ...h, past, present: next, future: [], lastKey: coalesce ?? null };
}

export const canUndo = <T>(h: History<T>): boolean => h.past.length > 0;
export const canRedo = <T>(h: History<T>): boolean => h.future.length > 0;

export function undo<T>(h: History<T>): History<T> {
  if (!canUndo(h)) return h;
  const past = h.past.slice(0, -1);
  return { ...h, past, present: h.past[h.past.length - 1], future: [h.present, ...h.future], lastKey: null };
}

export function redo<T>(h: History<T>): History<T> {
  if (!canRedo(h)) return h;
  const [next, ...future] = h.future;
  return { ...h, past: [...h.past, h.present], present: next, future, lastKey: null };
}

/** Replaces the present without an undo step (e.g. a reload from the server). */
export function reset<T>(h: History<T>, present: T): History<T> {
  return createHistory(present, h.limit);
}
