/**
 * Rehearsing an outage (training): the operator cuts the simulated link of a
 * `modd up --simulate` run (`make run`) and restores it, from the Monitor;
 * `modd link cut|restore` does the same from the command line. Shown only to
 * the operator and the admin, and only when the backend watches such a run
 * (a real drone's link is never cut from here). While cut, the drone keeps
 * archiving: *Fill gaps* after the restore recovers what the link missed.
 */
import { useEffect, useState } from "react";
import { useServices } from "../../app/services";
import type { Rehearsal as State } from "../../api/types";

export function Rehearsal({ drone }: { drone: string }) {
  const { api } = useServices();
  const [state, setState] = useState<State | null>(null);
  const [busy, setBusy] = useState(false);
  const [error, setError] = useState<string | null>(null);
  useEffect(() => {
    let live = true;
    api.rehearsal(drone).then((s) => { if (live) setState(s); }, () => undefined); // an older backend: no button
    return () => { live = false; };
  }, [api, drone]);
  if (!state?.available) return null;

  const toggle = async () => {
    setBusy(true);
    setError(null);
    try {
      setState(await api.setRehearsal(drone, !state.cut));
    } catch (e) {
      setError((e as Error).message);
    } finally {
      setBusy(false);
    }
  };
  return (
    <section className="rehearsal" aria-label="Rehearse an outage">
      <h3>Rehearse an outage</h3>
      <button type="button" className={state.cut ? "primary" : ""} onClick={() => void toggle()} disabled={busy}
        title={state.cut ? "Let the SubBroker reconnect to the drone" : "Drop the simulated link and keep it down (the drone archives on)"}>
        {state.cut ? "Restore the link" : "Cut the link"}
      </button>
      <p className="muted" role="status" data-testid="rehearsal-state">
        {state.cut ? "The simulated link is cut: values stop; the drone archives on. Restore it, then Fill gaps."
          : "The simulated link of this run (make run) is up."}
      </p>
      {error && <p className="error" role="alert">{error}</p>}
    </section>
  );
}
