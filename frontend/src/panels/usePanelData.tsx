/**
 * Loads something for a panel with loading / error / data states, and a
 * reload. A 404 is reported as "not provided by this backend" rather than as
 * a failure, so panels degrade gracefully against an older backend.
 */
import { useCallback, useEffect, useState } from "react";
import { ApiError } from "../api/http";

export type Loaded<T> =
  | { state: "loading" }
  | { state: "missing"; message: string }
  | { state: "error"; message: string }
  | { state: "ready"; data: T };

export function usePanelData<T>(load: (() => Promise<T>) | null, deps: unknown[]): [Loaded<T>, () => void] {
  const [value, setValue] = useState<Loaded<T>>({ state: "loading" });
  const [tick, setTick] = useState(0);
  const reload = useCallback(() => setTick((t) => t + 1), []);
  useEffect(() => {
    if (!load) return;
    let live = true;
    setValue((v) => (v.state === "ready" ? v : { state: "loading" }));
    load().then(
      (data) => { if (live) setValue({ state: "ready", data }); },
      (e: Error) => {
        if (!live) return;
        if (e instanceof ApiError && (e.status === 404 || e.status === 405)) setValue({ state: "missing", message: e.message });
        else setValue({ state: "error", message: e.message });
      },
    );
    return () => { live = false; };
    // eslint-disable-next-line react-hooks/exhaustive-deps
  }, [...deps, tick]);
  return [value, reload];
}

export function LoadState({ value, what }: { value: Loaded<unknown>; what: string }) {
  if (value.state === "loading") return <p role="status">Loading {what}…</p>;
  if (value.state === "missing") return <p className="muted" role="status">{what}: not provided by this backend ({value.message}).</p>;
  if (value.state === "error") return <p className="error" role="alert">{what}: {value.message}</p>;
  return null;
}
