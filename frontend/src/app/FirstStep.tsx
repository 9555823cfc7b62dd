/**
 * A short guided first step for each role view, shown the first time a
 * person opens that view (dismissed for good: kept in this browser).
 */
import { useState } from "react";
import type { ViewRole } from "../core/roles";
import { useEditor } from "../editor/useEditor";

const STEPS: Record<ViewRole, string> = {
  designer: "First step: select the PubBroker and the SubBroker to set the link's endpoints, then add a publisher with + Publisher and tick the topics it publishes in the inspector.",
  integrator: "First step: add a sensor with + Sensor, name it in the inspector, then add its measured variables with + Variable; the Downloads panel then gives the driver stubs.",
  scientist: "First step: pick a topic, a period and an aggregation in Quick subscription and press Subscribe; the Plan panel shows what it costs on the link.",
  operator: "First step: open the Deploy panel, check what changes against what the drone runs, and deploy the saved revision; the Monitor shows the live values.",
};

const KEY = (view: string) => `modd.firstStep.${view}`;

export function FirstStep() {
  const view = useEditor((s) => s.wb.role) as ViewRole;
  const [, redraw] = useState(0);
  let seen = true;
  try { seen = window.localStorage.getItem(KEY(view)) === "done"; } catch { /* storage off: show nothing */ }
  if (seen || !(view in STEPS)) return null;
  return (
    <div className="first-step" role="note" aria-label="First step">
      {STEPS[view]}
      <button onClick={() => { try { window.localStorage.setItem(KEY(view), "done"); } catch { /* */ } redraw((n) => n + 1); }}>Got it</button>
    </div>
  );
}
