/**
 * A short guided first step for each role view, shown the first time a
 * person opens that view (dismissed for good: kept in this browser).
 */
import { useState } from "react";
import type { ViewRole } from "../core/roles";
import { useEditor } from "../editor/useEditor";
import { currentModel } from "../core/workbench";

const STEPS: Record<ViewRole, string> = {
  designer: "First step: select the PubBroker and the SubBroker to set the link's endpoints, then add a publisher with + Publisher, set its period and press All of the sensor in the inspector.",
  integrator: "First step: fill New sensor (its name, its variables \"a, b, c\" and their unit) and press Add sensor; the Downloads panel then gives the driver stubs.",
  admin: "First step, every role in one view: fill New sensor and press Add sensor; + Publisher, its period and All of the sensor; then Quick subscription. The Plan panel follows each step.",
  scientist: "First step: pick a topic, a period and an aggregation in Quick subscription and press Subscribe; the Plan panel shows what it costs on the link.",
  operator: "First step: open the Deploy panel, check what changes against what the drone runs, and deploy the saved revision; the Monitor shows the live values.",
};

const KEY = (view: string) => `modd.firstStep.${view}`;

/** Before any sensor exists, the designer's publishers have nothing to publish: say who comes first. */
const DESIGNER_EMPTY = "First step: set the link's endpoints on the PubBroker and the SubBroker; publishers come once sensors exist (the Sensor integrator view's New sensor, or the All roles view).";

export function FirstStep() {
  const view = useEditor((s) => s.wb.role) as ViewRole;
  const noSensor = useEditor((s) => currentModel(s.wb).drone.sensors.length === 0);
  const [, redraw] = useState(0);
  let seen = true;
  try { seen = window.localStorage.getItem(KEY(view)) === "done"; } catch { /* storage off: show nothing */ }
  if (seen || !(view in STEPS)) return null;
  return (
    <div className="first-step" role="note" aria-label="First step">
      {view === "designer" && noSensor ? DESIGNER_EMPTY : STEPS[view]}
      <button onClick={() => { try { window.localStorage.setItem(KEY(view), "done"); } catch { /* */ } redraw((n) => n + 1); }}>Got it</button>
    </div>
  );
}
