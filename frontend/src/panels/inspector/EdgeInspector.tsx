/**
 * The inspector of a selected publisher → topic or topic → subscriber edge:
 * what it means in the model's words, its two ends (each one click away) and
 * Delete for a role that owns it (the publisher stops publishing the topic;
 * the subscriber is left without a topic until it is connected again). The
 * link edge is an element of its own (`link`) and gets the schema's form.
 */
import { parseId } from "../../core/ids";
import { listTopics } from "../../core/query";
import { canEditEdge } from "../../core/roles";
import { useEditorStore, useModel, useRole } from "../../editor/useEditor";
import { edgeEnds, removeSelection } from "../../editor/selectionActions";

export function EdgeInspector({ id }: { id: string }) {
  const store = useEditorStore();
  const model = useModel();
  const role = useRole();
  const ends = edgeEnds(id);
  if (!ends) return null;
  const kind = id.startsWith("publishes:") ? "publishes" : "subscribes";
  const topicEnd = kind === "publishes" ? ends.target : ends.source;
  const otherEnd = kind === "publishes" ? ends.source : ends.target;
  const topic = listTopics(model).find((t) => t.id === topicEnd)?.name ?? topicEnd;
  const other = parseId(otherEnd)?.name ?? otherEnd;
  const editable = canEditEdge(role, kind);
  const select = (to: string) => store.dispatch({ type: "select", ids: [to] });
  return (
    <section className="inspector" aria-label="Inspector">
      <h2>{kind === "publishes" ? "Publisher → topic" : "Topic → subscriber"}</h2>
      <p>
        {kind === "publishes"
          ? <><button className="link" onClick={() => select(otherEnd)}>{other}</button> publishes <button className="link" onClick={() => select(topicEnd)}>{topic}</button>.</>
          : <><button className="link" onClick={() => select(otherEnd)}>{other}</button> subscribes to <button className="link" onClick={() => select(topicEnd)}>{topic}</button>.</>}
      </p>
      <p className="kind-help">
        {kind === "publishes"
          ? "Deleting it removes the topic from what this publisher sends to the PubBroker."
          : "Deleting it leaves the subscriber without a topic until you connect one (drag from a topic to it)."}
      </p>
      {editable
        ? <button onClick={() => removeSelection(store)}>Delete this edge</button>
        : <p className="readonly-note" role="note">Read-only in the {role} view.</p>}
    </section>
  );
}
