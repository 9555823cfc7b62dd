/**
 * The palette: create elements (what the view's role may create) and the
 * diagram commands (undo, redo, delete, copy, paste, auto-layout, zoom to fit).
 */
import { useReactFlow } from "@xyflow/react";
import { canEdit, editsAnything } from "../core/roles";
import { canRedo, canUndo } from "../core/history";
import { nextPosition } from "../core/graph";
import { parseId } from "../core/ids";
import { currentModel } from "../core/workbench";
import { useEditor, useEditorStore, useRole, useSelection } from "./useEditor";
import { useAutoLayout } from "./useAutoLayout";
import { FIT } from "./fit";
import { removeSelection } from "./selectionActions";
import { QuickSubscribe } from "./QuickSubscribe";
import { QuickSensor } from "./QuickSensor";

/** The sensor a new variable goes to: the selected sensor, or the sensor of the selected topic, or the first. */
function targetSensor(selection: string[], sensors: string[]): string | undefined {
  for (const id of selection) {
    const p = parseId(id);
    if (p?.kind === "sensor" || p?.kind === "topic") return p.sensor;
  }
  return sensors[0];
}

export function Palette() {
  const store = useEditorStore();
  const role = useRole();
  const selection = useSelection();
  const history = useEditor((s) => s.wb.history);
  const hasClipboard = useEditor((s) => s.wb.clipboard !== null);
  const sensors = useEditor((s) => currentModel(s.wb).drone.sensors.map((x) => x.name).join("\n"));
  const flow = useReactFlow();
  const layout = useAutoLayout();
  const model = () => currentModel(store.getState().wb);
  const sensor = targetSensor(selection, sensors ? sensors.split("\n") : []);
  // The palette follows the view: in a view that edits nothing (Operator) the edit commands are off.
  const edits = editsAnything(role);
  const removable = selection.some((id) => { const k = parseId(id)?.kind; return k ? canEdit(role, k) : canEdit(role, "subscriber") || canEdit(role, "publisher"); });
  const offTitle = `The ${role} view does not edit the model`;

  return (
    <nav className="palette" aria-label="Palette">
      <h2>Create</h2>
      <button disabled={!canEdit(role, "sensor")} onClick={() => store.dispatch({ type: "addSensor", pos: nextPosition(model(), "sensor") })}>+ Sensor</button>
      {canEdit(role, "sensor") && canEdit(role, "topic") && <QuickSensor />}
      <button
        disabled={!canEdit(role, "topic") || !sensor}
        title={sensor ? `adds a measured variable to ${sensor}` : "add a sensor first"}
        onClick={() => sensor && store.dispatch({ type: "addVariable", sensor, pos: nextPosition(model(), "topic") })}
      >+ Variable</button>
      <button disabled={!canEdit(role, "publisher")} onClick={() => store.dispatch({ type: "addPublisher", pos: nextPosition(model(), "publisher") })}>+ Publisher</button>
      <button disabled={!canEdit(role, "subscriber")} onClick={() => store.dispatch({ type: "addSubscriber", pos: nextPosition(model(), "subscriber") })}>+ Subscriber</button>
      {canEdit(role, "subscriber") && <QuickSubscribe />}
      <h2>Edit</h2>
      <div className="palette-grid">
        <button aria-label="Undo" title={edits ? "Undo (Ctrl+Z)" : offTitle} disabled={!edits || !canUndo(history)} onClick={() => store.dispatch({ type: "undo" })}>↶ Undo</button>
        <button aria-label="Redo" title={edits ? "Redo (Ctrl+Shift+Z)" : offTitle} disabled={!edits || !canRedo(history)} onClick={() => store.dispatch({ type: "redo" })}>↷ Redo</button>
        <button aria-label="Copy" title={edits ? "Copy (Ctrl+C)" : offTitle} disabled={!edits || !selection.length} onClick={() => store.dispatch({ type: "copy", ids: selection })}>Copy</button>
        <button aria-label="Paste" title={edits ? "Paste (Ctrl+V)" : offTitle} disabled={!edits || !hasClipboard} onClick={() => store.dispatch({ type: "paste" })}>Paste</button>
        <button aria-label="Duplicate" title={edits ? "Duplicate the selection (Ctrl+D)" : offTitle} disabled={!edits || !selection.length} onClick={() => store.dispatch({ type: "duplicate", ids: selection })}>Duplicate</button>
        <button aria-label="Delete" title={edits ? "Delete (Del)" : offTitle} disabled={!edits || !removable} onClick={() => removeSelection(store)}>Delete</button>
      </div>
      <h2>View</h2>
      <button onClick={() => void layout.run()} disabled={layout.busy}>{layout.busy ? "Laying out…" : "Auto-layout"}</button>
      <button onClick={() => void flow.fitView(FIT)}>Zoom to fit</button>
    </nav>
  );
}
