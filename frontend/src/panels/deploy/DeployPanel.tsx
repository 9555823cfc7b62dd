/**
 * Deploy (operator): what a deploy would change on the drone, in the model's
 * words, with the plan's consequences (bytes/s, delays, hyperperiod before →
 * after); the deploy button (disabled, with the reason, for an invalid
 * revision); a warning when the drone runs another project; the drone's ack
 * or the error, and what each on-board process did with it (an instrument
 * whose device is missing said there); and the history, whose rows can be reviewed and redeployed
 * (a rollback is a redeploy of an older revision).
 */
import { useState } from "react";
import { canDeploy } from "../../core/roles";
import { useEditor } from "../../editor/useEditor";
import { isDirty } from "../../editor/store";
import { useServices } from "../../app/services";
import { usePanelData, LoadState } from "../usePanelData";
import type { Deployment } from "../../api/types";
import { loadDeployReview, type DeployReview } from "./useDeployReview";
import { onboardLines } from "../../core/onboard";
import { PairDrone } from "./PairDrone";

/** What each on-board process did with the deploy (modd-sensors, modd-mavlink), when they said. */
function OnboardResult({ reply }: { reply: Deployment["reply"] }) {
  const lines = onboardLines(reply?.onboard);
  if (lines.length === 0) return null;
  return (
    <ul className="onboard-result" aria-label="On-board processes" data-testid="deploy-onboard">
      {lines.map((l) => (
        <li key={l.process} className={l.ok ? "status-ok" : "error"} role={l.ok ? undefined : "alert"}>
          <strong>{l.process}</strong>: {l.text}
        </li>
      ))}
    </ul>
  );
}

function Review({ review }: { review: DeployReview }) {
  const { diff, candidate, changes, consequences, otherProject } = review;
  return (
    <>
      <p>Drone <strong>{diff.drone}</strong>: {diff.deployed
        ? <>runs revision {diff.deployed.revision}{otherProject ? ` of project ${otherProject}` : ""}, deployed by {diff.deployed.requested_by}</>
        : "nothing deployed yet"}.</p>
      {otherProject && (
        <p className="warning-banner" role="alert" data-testid="other-project">
          The drone runs project <strong>{otherProject}</strong>: deploying replaces it with revision {candidate.revision} of this project.
        </p>
      )}
      <h4>Changes on the drone (revision {candidate.revision})</h4>
      {changes.length === 0 ? <p className="muted">No difference.</p> : (
        <ul className="change-list" aria-label="Model changes">
          {changes.slice(0, 80).map((c) => <li key={c.pointer} className={`diff-${c.op}`}>{c.text}</li>)}
          {changes.length > 80 && <li className="muted">… and {changes.length - 80} more</li>}
        </ul>
      )}
      {consequences.length > 0 && (
        <table className="consequence-table" aria-label="Plan consequences">
          <thead><tr><th>Plan</th><th>Before</th><th /><th>After</th></tr></thead>
          <tbody>{consequences.slice(0, 40).map((c) => (
            <tr key={c.key}><td>{c.label}</td><td>{c.before}</td><td>→</td><td><strong>{c.after}</strong></td></tr>
          ))}</tbody>
        </table>
      )}
    </>
  );
}

export default function DeployPanel() {
  const { api } = useServices();
  const project = useEditor((s) => s.project);
  const role = useEditor((s) => s.wb.role);
  const head = useEditor((s) => s.savedRevision);
  const dirty = useEditor(isDirty);
  const [picked, setPicked] = useState<number | null>(null);
  const [progress, setProgress] = useState<{ busy: boolean; result: Deployment | null; error: string | null }>({ busy: false, result: null, error: null });
  const pid = project?.id ?? 0;
  const revision = picked ?? head;
  const [review, reloadReview] = usePanelData(project && revision ? () => loadDeployReview(api, pid, revision) : null, [pid, revision]);
  const [history, reloadHistory] = usePanelData(project ? () => api.listDeployments(pid) : null, [pid, head]);

  const blockers = review.state === "ready" ? review.data.blockers : [];
  const reason = !canDeploy(role) ? "only the operator deploys"
    : revision === 0 ? "nothing saved yet"
      : review.state !== "ready" ? "checking the revision…"
        : blockers.length ? `revision ${revision} has ${blockers.length} error(s): fix them before deploying` : null;

  const deploy = async (rev: number) => {
    setProgress({ busy: true, result: null, error: null });
    try {
      const d = await api.deploy(pid, rev);
      setProgress({ busy: false, result: d, error: d.status === "acked" ? null : d.error ?? d.status });
    } catch (e) {
      setProgress({ busy: false, result: null, error: (e as Error).message });
    }
    reloadReview();
    reloadHistory();
  };

  return (
    <div className="panel-body deploy-panel">
      <div className="deploy-actions">
        <button className="primary" onClick={() => void deploy(revision)} disabled={reason !== null || progress.busy}
          title={reason ?? `deploy revision ${revision}`}>
          {progress.busy ? "Deploying… waiting for the drone" : `Deploy revision ${revision}`}
        </button>
        {picked !== null && picked !== head && <button onClick={() => setPicked(null)}>Back to the head (revision {head})</button>}
        {reason && review.state === "ready" && <span className="error" data-testid="deploy-blocked">Deploy disabled: {reason}.</span>}
        {!canDeploy(role) && <span className="muted">Only the operator view deploys.</span>}
        {dirty && <span className="muted">Unsaved edits are not deployed: save first.</span>}
        {progress.result?.status === "acked" && <span className="status-ok" role="status" data-testid="deploy-result">Acked by the drone ({progress.result.drone}, revision {progress.result.revision}).</span>}
        {progress.error && <span className="error" role="alert" data-testid="deploy-result">Deploy failed: {progress.error}</span>}
      </div>
      {progress.result?.status === "acked" && <OnboardResult reply={progress.result.reply} />}
      {blockers.length > 0 && (
        <ul className="problem-list" aria-label="Why deploy is disabled">
          {blockers.slice(0, 12).map((b, i) => <li key={i}><strong>{b.element}</strong>: {b.text}</li>)}
        </ul>
      )}
      <div className="deploy-grid">
        <section aria-label="Deployed against edited">
          <h3>Deployed vs revision {revision}</h3>
          <LoadState value={review} what="the deployed diff" />
          {review.state === "ready" && <Review review={review.data} />}
        </section>
        <section aria-label="Deployment history">
          <h3>History</h3>
          <LoadState value={history} what="deployments" />
          {history.state === "ready" && (history.data.length === 0 ? <p className="muted">No deployment yet.</p> : (
            <table className="history-table">
              <thead><tr><th>#</th><th>Revision</th><th>Drone</th><th>By</th><th>When</th><th>Result</th><th /></tr></thead>
              <tbody>{history.data.map((d) => (
                <tr key={d.id} className={d.revision === revision ? "picked" : ""}>
                  <td>{d.id}</td><td>{d.revision}</td><td>{d.drone}</td><td>{d.requested_by}</td>
                  <td>{new Date(d.requested_at).toLocaleString(undefined, { dateStyle: "short", timeStyle: "short" })}</td>
                  <td className={d.status === "acked" ? "status-ok" : "error"}>{d.status}{d.error ? `: ${d.error}` : ""}</td>
                  <td>
                    <button className="link" onClick={() => setPicked(d.revision)} aria-label={`Review revision ${d.revision} (deployment ${d.id})`}>diff</button>
                    {" "}<button className="link" disabled={!canDeploy(role) || progress.busy}
                      onClick={() => { setPicked(d.revision); void deploy(d.revision); }}
                      aria-label={`Redeploy revision ${d.revision} (deployment ${d.id})`}>redeploy</button>
                  </td>
                </tr>
              ))}</tbody>
            </table>
          ))}
        </section>
      </div>
      <PairDrone projectId={pid} revision={revision} allowed={canDeploy(role)} />
    </div>
  );
}
