/**
 * Generated artefacts per role, as zips from the backend's generators:
 * driver stubs (integrator), broker configs (operator), subscriber stubs
 * (scientist). Also the model itself as .modd or JSON.
 */
import { useState } from "react";
import { useEditor } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { saveBlob } from "../saveBlob";

import { TARGETS } from "./targets";
import { RemadeCredentials } from "./RemadeCredentials";


export default function DownloadsPanel() {
  const { api } = useServices();
  const project = useEditor((s) => s.project);
  const revision = useEditor((s) => s.savedRevision);
  const [status, setStatus] = useState<Record<string, string>>({});
  const [live, setLive] = useState<string | null>(null);
  if (!project) return <div className="panel-body">No project.</div>;

  const get = async (target: string, name: string, fetcher: () => Promise<Blob | string>) => {
    setStatus((s) => ({ ...s, [target]: "downloading…" }));
    try {
      const body = await fetcher();
      saveBlob(typeof body === "string" ? new Blob([body], { type: "text/plain" }) : body, name);
      setStatus((s) => ({ ...s, [target]: "done" }));
    } catch (e) {
      setStatus((s) => ({ ...s, [target]: (e as Error).message }));
    }
  };

  return (
    <div className="panel-body downloads-panel">
      <RemadeCredentials />
      <p className="muted">Generated from the saved revision {revision}; save first to include unsaved edits.</p>
      <ul className="download-list">
        {TARGETS.map((t) => (
          <li key={t.target}>
            <button onClick={() => void get(t.target, `${project.name}-r${revision}-${t.target}.zip`, () => api.download(project.id, t.target))}>
              Download {t.title}
            </button>
            <span className="muted"> for the {t.who}</span>
            {status[t.target] && <span role="status"> — {status[t.target]}</span>}
          </li>
        ))}
        <li>
          <button onClick={() => void get("foxglove", `${project.name}-r${revision}-foxglove-layout.json`, () => api.foxgloveLayout(project.id))}>
            Download the Foxglove layout
          </button>
          <span className="muted"> for the Scientist: open it in Foxglove or Lichtblick against the base station's Foxglove server</span>
          {status.foxglove && <span role="status"> — {status.foxglove}</span>}
        </li>
        <li>
          <button onClick={() => void api.foxgloveLinks().then(
            (l) => { setLive(l.live ?? "this backend runs no Foxglove server"); },
            (e: Error) => { setLive(e.message); })}>
            Foxglove link
          </button>
          <span className="muted"> the live mission in Foxglove or Lichtblick (Open connection → Foxglove WebSocket); opens one connection, within 5 minutes</span>
          {live && <code role="status" aria-label="Foxglove live link"> {live}</code>}
        </li>
        <li>
          <button onClick={() => void get("modd", `${project.name}-r${revision}.modd`, () => api.exportModel(project.id, "modd"))}>Download the model (.modd)</button>
          {status.modd && <span role="status"> — {status.modd}</span>}
        </li>
        <li>
          <button onClick={() => void get("json", `${project.name}-r${revision}.json`, () => api.exportModel(project.id, "json"))}>Download the model (JSON, with layout)</button>
          {status.json && <span role="status"> — {status.json}</span>}
        </li>
        <li>
          <button onClick={() => void get("collector", `${project.name}-r${revision}.collector`, () => api.exportModel(project.id, "collector"))}>Download for the original MoDD tool (.collector)</button>
          <span className="muted"> opens with a comment per thing that form cannot hold</span>
          {status.collector && <span role="status"> — {status.collector}</span>}
        </li>
      </ul>
    </div>
  );
}
