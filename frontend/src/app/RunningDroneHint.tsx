/**
 * In an empty project: which PubBroker and SubBroker ports the running drone
 * uses (core/runningDrone.ts), with a button that makes them this model's.
 * Asked once when the project opens; says nothing when no drone reports.
 */
import { useEffect, useState } from "react";
import type { RunningDrone } from "../api/types";
import { canEdit } from "../core/roles";
import { runningHint } from "../core/runningDrone";
import { useEditor, useEditorStore, useModel } from "../editor/useEditor";
import { useServices } from "./services";

export function RunningDroneHint() {
  const { api } = useServices();
  const store = useEditorStore();
  const model = useModel();
  const role = useEditor((s) => s.wb.role);
  const [running, setRunning] = useState<RunningDrone[]>([]);
  useEffect(() => {
    let live = true;
    api.runningDrones().then((r) => { if (live) setRunning(r); }).catch(() => undefined);
    return () => { live = false; };
  }, [api]);
  const hint = runningHint(model, running);
  if (!hint) return null;
  return (
    <div className="first-step" role="note" aria-label="Running drone">
      {hint.text}
      {hint.edits.length > 0 && canEdit(role, "pubBroker") && (
        <button onClick={() => hint.edits.forEach((e) => store.dispatch({ type: "setField", ...e }))}>Use these endpoints</button>
      )}
    </div>
  );
}
