/**
 * The live plan: recomputed by the backend's planning engine as you edit
 * (debounced in useLivePlan). Hyperperiod, the schedule's timeline, buffer
 * sizes per topic with each subscriber's delay, predicted link bytes/s
 * against plain pub/sub, the declared transport's link budget, and what is
 * infeasible and why.
 */
import { formatRate, topicRows } from "../../core/plan";
import { subscriberId, topicId } from "../../core/ids";
import { findTopicByName } from "../../core/query";
import { useEditor, useEditorStore, useModel } from "../../editor/useEditor";
import { LinkBudgetView } from "./LinkBudget";
import { Timeline } from "./Timeline";

export default function PlanPanel() {
  const store = useEditorStore();
  const model = useModel();
  const { busy, result, error } = useEditor((s) => s.plan);
  const select = (id: string) => store.dispatch({ type: "select", ids: [id] });

  if (error) return <div className="panel-body"><p className="error" role="alert">Plan unavailable: {error}</p></div>;
  if (!result) return <div className="panel-body" role="status">{busy ? "Planning…" : "No plan yet."}</div>;
  const plan = result.plan;
  if (!plan) {
    const errors = result.diagnostics.filter((d) => d.severity === "error");
    return (
      <div className="panel-body">
        <p role="status">The model has {errors.length} error(s); the plan needs a valid model.</p>
        <ul className="problem-list">{errors.slice(0, 12).map((d, i) => <li key={i}><code>{d.pointer}</code> {d.message}</li>)}</ul>
      </div>
    );
  }
  const link = plan.predicted_link_bytes_per_s;
  const rows = topicRows(plan);
  return (
    <div className="panel-body plan-panel" aria-busy={busy}>
      <div className="plan-summary">
        <div className="figure"><span>Hyperperiod</span><strong data-testid="hyperperiod">{plan.hyperperiod_s} s</strong></div>
        <div className="figure"><span>Messages / hyperperiod</span><strong>{plan.messages_per_hyperperiod}</strong></div>
        <div className="figure"><span>Link, drone → base</span><strong>{formatRate(link.drone_to_base)}</strong></div>
        <div className="figure"><span>Plain pub/sub</span><strong>{formatRate(link.plain_pubsub)}</strong></div>
        <div className="figure"><span>Saving</span><strong>{(link.saving_ratio * 100).toFixed(1)} %</strong></div>
        <div className="figure"><span>Max delay</span><strong>{plan.max_delay_s} s</strong></div>
        <div className="figure muted"><span>Planned in</span><strong>{result.elapsed_ms.toFixed(0)} ms</strong></div>
      </div>
      {plan.link_budget && <LinkBudgetView budget={plan.link_budget} onSelect={(n) => select(subscriberId(n))} />}
      {(plan.infeasible.length > 0 || plan.violates_delay_cap) && (
        <div className="infeasible" role="alert">
          <strong>Infeasible</strong>
          <ul>
            {plan.infeasible.map((x, i) => (
              <li key={i}>
                <button className="link" onClick={() => { const t = findTopicByName(model, x.topic); if (t) select(t.id); }}>{x.topic}</button>
                {x.subscribers.length > 0 && <> ({x.subscribers.join(", ")})</>}: {x.reason}
              </li>
            ))}
            {plan.violates_delay_cap && <li>a subscriber's delay exceeds the cap of 3 × PING</li>}
          </ul>
        </div>
      )}
      <div className="plan-grid">
        <table className="buffer-table" aria-label="Buffer sizes">
          <thead><tr><th>Topic</th><th>Published every</th><th>Buffer size</th><th>Subscribers (delay)</th></tr></thead>
          <tbody>
            {rows.map((r) => {
              const t = findTopicByName(model, r.topic);
              return (
                <tr key={r.topic}>
                  <td><button className="link" onClick={() => t && select(topicId(t.sensor.name, t.variable.name))}>{r.topic}</button></td>
                  <td>{r.publicationPeriodS ?? "—"} s</td>
                  <td className="buffer-size" data-testid="buffer-size">{r.bufferSize ?? "—"}</td>
                  <td>{r.subscribers.map((s) => (
                    <button key={s.name} className="link chip" onClick={() => select(subscriberId(s.name))} title={s.stream}>
                      {s.name} ({s.delayS ?? "?"} s)
                    </button>
                  ))}</td>
                </tr>
              );
            })}
          </tbody>
        </table>
        <Timeline plan={plan} />
      </div>
    </div>
  );
}
