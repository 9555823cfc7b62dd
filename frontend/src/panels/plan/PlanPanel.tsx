/**
 * The live plan: recomputed by the backend's planning engine as you edit
 * (debounced in useLivePlan). Hyperperiod, the schedule's timeline, buffer
 * sizes per topic with each subscriber's delay, predicted link bytes/s
 * against plain pub/sub, the declared transport's link budget, and what is
 * infeasible and why.
 *
 * After an edit, what changed in the plan is listed and highlighted (before
 * → after, core/planDiff). While the model has errors, the last valid plan
 * stays on screen, greyed, under the errors in words (core/diagnosticWords).
 */
import { formatRate, topicRows, type PlanJson } from "../../core/plan";
import { planChanges, type PlanChange } from "../../core/planDiff";
import { diagnosticsInWords } from "../../core/diagnosticWords";
import { subscriberId, topicId } from "../../core/ids";
import { findTopicByName } from "../../core/query";
import { topicLabel } from "../../core/topicLabel";
import { useEditor, useEditorStore, useModel } from "../../editor/useEditor";
import { AirTimeView } from "./AirTime";
import { CalibrationPicker } from "./Calibration";
import { LinkBudgetView } from "./LinkBudget";
import { SCHEDULE_DELAY_HELP } from "./delayWords";
import { Timeline } from "./Timeline";

function PlanChanges({ changes }: { changes: PlanChange[] }) {
  if (changes.length === 0) return null;
  return (
    <div className="plan-changes" role="status" aria-label="Plan changes">
      <strong>Changed by the last edit</strong>
      <ul>{changes.slice(0, 12).map((c) => <li key={c.key}>{c.label}: {c.before} → <strong>{c.after}</strong></li>)}
        {changes.length > 12 && <li className="muted">… and {changes.length - 12} more</li>}</ul>
    </div>
  );
}

interface ViewProps { plan: PlanJson; changed: Map<string, PlanChange>; stale: boolean; elapsedMs: number; busy: boolean }

function PlanView({ plan, changed, stale, elapsedMs, busy }: ViewProps) {
  const store = useEditorStore();
  const model = useModel();
  const select = (id: string) => store.dispatch({ type: "select", ids: [id] });
  const mark = (key: string) => (changed.has(key) ? "changed" : undefined);
  const was = (key: string) => (changed.has(key) ? `was ${changed.get(key)!.before}` : undefined);
  const link = plan.predicted_link_bytes_per_s;
  const rows = topicRows(plan);
  return (
    <div className={`plan-panel${stale ? " plan-stale" : ""}`} aria-busy={busy} data-testid={stale ? "plan-stale" : "plan-current"}>
      <div className="plan-summary">
        <div className="figure"><span>Hyperperiod</span><strong data-testid="hyperperiod" className={mark("hyperperiod")} title={was("hyperperiod")}>{plan.hyperperiod_s} s</strong></div>
        <div className="figure"><span>Messages / hyperperiod</span><strong className={mark("messages")} title={was("messages")}>{plan.messages_per_hyperperiod}</strong></div>
        <div className="figure"><span>Link, drone → base</span><strong className={mark("bytes")} title={was("bytes")}>{formatRate(link.drone_to_base)}</strong></div>
        <div className="figure"><span>Plain pub/sub</span><strong>{formatRate(link.plain_pubsub)}</strong></div>
        <div className="figure"><span>Saving</span><strong>{(link.saving_ratio * 100).toFixed(1)} %</strong></div>
        <div className="figure" title={SCHEDULE_DELAY_HELP}><span>Max schedule delay</span><strong className={mark("maxDelay")} title={was("maxDelay")}>{plan.max_delay_s} s</strong></div>
        <div className="figure muted"><span>Planned in</span><strong>{elapsedMs.toFixed(0)} ms</strong></div>
      </div>
      {plan.link_budget && <LinkBudgetView budget={plan.link_budget} onSelect={(n) => select(subscriberId(n))} />}
      {plan.radio && <CalibrationPicker drone={model.drone.name} />}
      {plan.radio && <AirTimeView radio={plan.radio} onSelect={(n) => select(subscriberId(n))} />}
      {(plan.infeasible.length > 0 || plan.violates_delay_cap) && (
        <div className="infeasible" role="alert">
          <strong>Infeasible</strong>
          <ul>
            {plan.infeasible.map((x, i) => (
              <li key={i}>
                <button className="link" onClick={() => { const t = findTopicByName(model, x.topic); if (t) select(t.id); }}>{topicLabel(model, x.topic)}</button>
                {x.subscribers.length > 0 && <> ({x.subscribers.join(", ")})</>}: {x.reason}
              </li>
            ))}
            {plan.violates_delay_cap && <li>a subscriber's delay exceeds the cap of 3 × PING</li>}
          </ul>
        </div>
      )}
      <div className="plan-grid">
        <table className="buffer-table" aria-label="Buffer sizes">
          <thead><tr><th>Topic</th><th>Published every</th><th>Buffer size</th><th title={SCHEDULE_DELAY_HELP}>Subscribers (schedule delay)</th></tr></thead>
          <tbody>
            {rows.map((r) => {
              const t = findTopicByName(model, r.topic);
              return (
                <tr key={r.topic}>
                  <td><button className="link" onClick={() => t && select(topicId(t.sensor.name, t.variable.name))}>{topicLabel(model, r.topic)}</button></td>
                  <td>{r.publicationPeriodS ?? "—"} s</td>
                  <td className="buffer-size" data-testid="buffer-size"><span className={mark(`buffer:${r.topic}`)} title={was(`buffer:${r.topic}`)}>{r.bufferSize ?? "—"}</span></td>
                  <td>{r.subscribers.map((s) => (
                    <button key={s.name} className={`link chip ${mark(`delay:${s.name}`) ?? ""}`} onClick={() => select(subscriberId(s.name))}
                      title={[s.stream, was(`delay:${s.name}`)].filter(Boolean).join(" · ")}>
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


export default function PlanPanel() {
  const model = useModel();
  const { busy, result, error, lastValid, previous } = useEditor((s) => s.plan);

  if (error && !lastValid) return <div className="panel-body"><p className="error" role="alert">Plan unavailable: {error}</p></div>;
  if (!result) return <div className="panel-body" role="status">{busy ? "Planning…" : "No plan yet."}</div>;
  const plan = result.plan;
  const errors = diagnosticsInWords(model, result.diagnostics.filter((d) => d.severity === "error"));
  const changes = plan ? planChanges(previous ?? null, plan, (t) => topicLabel(model, t)) : [];
  const shown = plan ?? lastValid ?? null;
  return (
    <div className="panel-body">
      {error && <p className="error" role="alert">Plan unavailable: {error}</p>}
      {!plan && (
        <div className="plan-errors" role="alert" aria-label="Plan errors">
          <p role="status">The model has {errors.length} error(s); the plan needs a valid model.{shown ? " The last valid plan is shown greyed below." : ""}</p>
          <ul className="problem-list">{errors.slice(0, 12).map((d, i) => <li key={i}><strong>{d.element}</strong>: {d.text}</li>)}</ul>
        </div>
      )}
      {plan && <PlanChanges changes={changes} />}
      {shown && <PlanView plan={shown} stale={!plan} busy={busy} elapsedMs={result.elapsed_ms}
        changed={new Map(changes.map((c) => [c.key, c]))} />}
    </div>
  );
}
