/**
 * Deploy (operator): what runs on the drone against the saved head (the
 * backend's diff), the deploy button, the drone's ack or the error, and the
 * history of deployments.
 */
import { useState } from "react";
import { canDeploy } from "../../core/roles";
import { useEditor } from "../../editor/useEditor";
import { isDirty } from "../../editor/store";
import { useServices } from "../../app/services";
import { usePanelData, LoadState } from "../usePanelData";
import type { Deployment } from "../../api/types";

function describe(v: unknown): string {
  if (v === undefined) return "";
  const s = JSON.stringify(v);
  return s.length > 80 ? `${s.slice(0, 77)}…` : s;
}

export default function DeployPanel() {
  const { api } = useServices();
  const project = useEditor((s) => s.project);
  const role = useEditor((s) => s.wb.role);
  const revision = useEditor((s) => s.savedRevision);
  const dirty = useEditor(isDirty);
  const [progress, setProgress] = useState<{ busy: boolean; result: Deployment | null; error: string | null }>({ busy: false, result: null, error: null });
  const pid = project?.id ?? 0;
  const [diff, reloadDiff] = usePanelData(project ? () => api.deployedDiff(pid) : null, [pid, revision]);
  const [history, reloadHistory] = usePanelData(project ? () => api.listDeployments(pid) : null, [pid, revision]);

  // The layout is presentation: it changes nothing on the drone.
  const changes = diff.state === "ready" ? diff.data.changes.filter((c) => !c.pointer.startsWith("/layout")) : [];

  const deploy = async () => {
    setProgress({ busy: true, result: null, error: null });
    try {
      const d = await api.deploy(pid, revision);
      setProgress({ busy: false, result: d, error: d.status === "acked" ? null : d.error ?? d.status });
    } catch (e) {
      setProgress({ busy: false, result: null, error: (e as Error).message });
    }
    reloadDiff();
    reloadHistory();
  };

  return (
    <div className="panel-body deploy-panel">
      <div className="deploy-actions">
        <button className="primary" onClick={() => void deploy()} disabled={!canDeploy(role) || progress.busy || revision === 0}
          title={canDeploy(role) ? `deploy revision ${revision}` : "only the operator deploys"}>
          {progress.busy ? "Deploying… waiting for the drone" : `Deploy revision ${revision}`}
        </button>
        {!canDeploy(role) && <span className="muted">Only the operator view deploys.</span>}
        {dirty && <span className="muted">Unsaved edits are not deployed: save first.</span>}
        {progress.result?.status === "acked" && <span className="status-ok" role="status" data-testid="deploy-result">Acked by the drone ({progress.result.drone}, revision {progress.result.revision}).</span>}
        {progress.error && <span className="error" role="alert" data-testid="deploy-result">Deploy failed: {progress.error}</span>}
      </div>
      <div className="deploy-grid">
        <section aria-label="Deployed against edited">
          <h3>Deployed vs saved head</h3>
          <LoadState value={diff} what="the deployed diff" />
          {diff.state === "ready" && (
            <>
              <p>Drone <strong>{diff.data.drone}</strong>: {diff.data.deployed
                ? <>runs revision {diff.data.deployed.revision}{diff.data.same_project ? "" : ` of project ${diff.data.deployed.project_id}`}, deployed by {diff.data.deployed.requested_by}</>
                : "nothing deployed yet"}.</p>
              {changes.length === 0 ? <p className="muted">No difference.</p> : (
                <table className="diff-table"><tbody>
                  {changes.slice(0, 60).map((c, i) => (
                    <tr key={i} className={`diff-${c.op}`}><td>{c.op}</td><td><code>{c.pointer}</code></td><td>{describe(c.before)}</td><td>{describe(c.after)}</td></tr>
                  ))}
                </tbody></table>
              )}
            </>
          )}
        </section>
        <section aria-label="Deployment history">
          <h3>History</h3>
          <LoadState value={history} what="deployments" />
          {history.state === "ready" && (history.data.length === 0 ? <p className="muted">No deployment yet.</p> : (
            <table className="history-table">
              <thead><tr><th>#</th><th>Revision</th><th>Drone</th><th>By</th><th>When</th><th>Result</th></tr></thead>
              <tbody>{history.data.map((d) => (
                <tr key={d.id}><td>{d.id}</td><td>{d.revision}</td><td>{d.drone}</td><td>{d.requested_by}</td>
                  <td>{new Date(d.requested_at).toLocaleString()}</td><td className={d.status === "acked" ? "status-ok" : "error"}>{d.status}{d.error ? `: ${d.error}` : ""}</td></tr>
              ))}</tbody>
            </table>
          ))}
        </section>
      </div>
    </div>
  );
}
