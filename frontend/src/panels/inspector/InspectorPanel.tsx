/**
 * The inspector: a form generated from the JSON Schema for the selected
 * element, with the schema's descriptions as help and the diagnostics of each
 * field under it. Read-only when the view's role may not edit the element.
 */
import { useMemo, useRef } from "react";
import { parseId, type ElementKind } from "../../core/ids";
import { elementValue } from "../../core/ops";
import { getPath, kindDescription, shownFields } from "../../core/schemaForm";
import { MODD_SCHEMA } from "../../core/schema";
import { listTopics } from "../../core/query";
import { placeDiagnostics } from "../../core/diagnostics";
import { canEdit } from "../../core/roles";
import { useEditorStore, useModel, useRole, useSelection } from "../../editor/useEditor";
import { useDiagnostics } from "../../editor/useFlowElements";
import { edgeEnds, removeSelection } from "../../editor/selectionActions";
import { KIND_LABEL } from "../../editor/nodes/ElementNode";
import { EdgeInspector } from "./EdgeInspector";
import { FieldInput } from "./FieldInput";
import { CampaignForm } from "./CampaignForm";

export default function InspectorPanel() {
  const store = useEditorStore();
  const model = useModel();
  const role = useRole();
  const selection = useSelection();
  const diagnostics = useDiagnostics();
  const placed = useMemo(() => placeDiagnostics(model, diagnostics), [model, diagnostics]);
  const topics = useMemo(() => listTopics(model), [model]);
  // The form stays mounted across a rename of its element (typing a name keeps the focus);
  // choosing another element gives fresh fields.
  const slot = useRef({ id: "", n: 0 });

  const nodeIds = selection.filter((id) => parseId(id));
  const edgeIds = selection.filter((id) => edgeEnds(id));
  if (nodeIds.length === 0 && edgeIds.length === 1) return <EdgeInspector id={edgeIds[0]} />;
  if (nodeIds.length === 0 && edgeIds.length > 1) {
    return (
      <section className="inspector" aria-label="Inspector">
        <h2>{edgeIds.length} edges selected</h2>
        <button onClick={() => removeSelection(store)}>Delete selection</button>
      </section>
    );
  }
  if (nodeIds.length === 0) {
    const problems = placed.filter((d) => d.severity === "error");
    return (
      <section className="inspector" aria-label="Inspector">
        <h2>Inspector</h2>
        <p className="muted">Select an element on the diagram to edit it.</p>
        {problems.length > 0 && (
          <>
            <h3>{problems.length} problem(s)</h3>
            <ul className="problem-list">
              {problems.map((d, i) => (
                <li key={i}><button className="link" onClick={() => store.dispatch({ type: "select", ids: [d.elementId] })}>{d.elementId}</button>: {d.message}</li>
              ))}
            </ul>
          </>
        )}
        <CampaignForm />
      </section>
    );
  }
  if (nodeIds.length > 1) {
    return (
      <section className="inspector" aria-label="Inspector">
        <h2>{nodeIds.length} elements selected</h2>
        <button onClick={() => removeSelection(store)}>Delete selection</button>
      </section>
    );
  }
  const id = nodeIds[0];
  if (slot.current.id !== id) {
    const renamed = slot.current.id !== "" && elementValue(model, slot.current.id) === undefined;
    slot.current = { id, n: renamed ? slot.current.n : slot.current.n + 1 };
  }
  const kind = parseId(id)!.kind as ElementKind;
  const value = elementValue(model, id);
  if (!value) return <section className="inspector"><p>This element no longer exists.</p></section>;
  const readOnly = !canEdit(role, kind);
  const parsed = parseId(id)!;
  const sensorKind = kind === "topic" ? model.drone.sensors.find((x) => x.name === parsed.sensor)?.kind
    : kind === "sensor" ? (value as { kind?: string }).kind : undefined;
  const mine = placed.filter((d) => d.elementId === id);
  const fieldErrors = (path: string[]) => mine.filter((d) => d.field.slice(0, path.length).join("/") === path.join("/") && d.field.length >= path.length).map((d) => d.message);
  const general = mine.filter((d) => d.field.length === 0).map((d) => d.message);

  return (
    <section className="inspector" aria-label="Inspector">
      <h2>{KIND_LABEL[kind]} {"name" in value ? String((value as { name?: string }).name ?? "") : ""}</h2>
      <p className="kind-help">{kindDescription(MODD_SCHEMA, kind)}</p>
      {readOnly && <p className="readonly-note" role="note">Read-only in the {role} view.</p>}
      {general.map((m) => <div key={m} className="field-error" role="alert">{m}</div>)}
      <form onSubmit={(e) => e.preventDefault()}>
        {shownFields(MODD_SCHEMA, kind, sensorKind).map((spec) => (
          <FieldInput key={`${slot.current.n}/${kind}/${spec.path.join(".")}`} spec={spec} value={getPath(value, spec.path)} topics={topics}
            readOnly={readOnly} errors={fieldErrors(spec.path)}
            onCommit={(v) => store.dispatch({ type: "setField", id, path: spec.path, value: v })} />
        ))}
      </form>
      {kind === "drone" && <CampaignForm />}
    </section>
  );
}
