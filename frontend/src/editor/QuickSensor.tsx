/**
 * The integrator's shortcut: a sensor with all its variables in one form —
 * its name, the variables ("accel_x, accel_y, accel_z", each may say its own
 * unit as "temp:degC") and their unit, offered as UDUNITS strings with their
 * symbols (core/unitChoices) — added as one edit
 * (core/sensorForm.ts), one undo step.
 */
import { useState } from "react";
import { unitChoices } from "../core/unitChoices";
import { EditError } from "../core/ops";
import { nextPosition } from "../core/graph";
import { parseVariables, withSensor } from "../core/sensorForm";
import { currentModel } from "../core/workbench";
import { useEditorStore } from "./useEditor";

const UNITS = unitChoices();

export function QuickSensor() {
  const store = useEditorStore();
  const [name, setName] = useState("");
  const [text, setText] = useState("");
  const [unit, setUnit] = useState("1");
  const [error, setError] = useState<string | null>(null);
  const { variables, bad } = parseVariables(text, unit);
  return (
    <form className="quick-subscribe" aria-label="New sensor" onSubmit={(e) => {
      e.preventDefault();
      const model = currentModel(store.getState().wb);
      try {
        store.dispatch({ type: "replaceModel", model: withSensor(model, name.trim(), variables, nextPosition(model, "sensor")) });
        setName(""); setText(""); setError(null);
      } catch (err) {
        if (!(err instanceof EditError)) throw err;
        setError(err.message);
      }
    }}>
      <label>Sensor name
        <input value={name} onChange={(e) => setName(e.target.value)} placeholder="accelerometer" />
      </label>
      <label>Variables
        <input value={text} onChange={(e) => setText(e.target.value)} placeholder="accel_x, accel_y, accel_z"
          aria-invalid={bad.length > 0} title="Names separated by commas; name:UNIT gives one its own unit" />
      </label>
      <label>Unit
        <input value={unit} onChange={(e) => setUnit(e.target.value)} list="quick-sensor-units"
          title="A UDUNITS unit as CF writes it (m s-2, degC) or its symbol (m/s², °C): type either to search" />
        <datalist id="quick-sensor-units">{UNITS.map((u) => <option key={u.value} value={u.value} label={u.label} />)}</datalist>
      </label>
      {(bad.length > 0 || error) && <span className="error" role="alert">{bad.length ? `Not a variable name: ${bad.join(", ")}` : error}</span>}
      <button type="submit" disabled={!name.trim() || !variables.length || bad.length > 0}>
        Add sensor{variables.length > 1 ? ` (${variables.length} variables)` : ""}
      </button>
    </form>
  );
}
