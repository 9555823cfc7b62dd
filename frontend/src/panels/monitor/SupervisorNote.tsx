/**
 * Why the run stopped, when `modd up` gave it up (the status' `supervisor`,
 * docs/reliability.md "Base station, store and tools"): which process, its exit
 * code, the supervisor's reason and where its log is on the base station.
 */
import { gaveUpWords } from "../../core/linkHealth";
import type { SupervisorStop } from "../../dataSources/types";

export function SupervisorNote({ stop }: { stop: SupervisorStop }) {
  return (
    <p className="error supervisor-stop" role="alert" aria-label="Run stopped" data-testid="supervisor-stop">
      <strong>{gaveUpWords(stop)}</strong>
      {stop.log && <> · its log on the base station: <code>{stop.log}</code></>}
      {" "}· start it again with <code>modd up</code> once the cause is fixed.
    </p>
  );
}
