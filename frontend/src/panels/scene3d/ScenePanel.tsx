/** The backend's viser scene (drone track and attitude), embedded. */
import { useServices } from "../../app/services";
import { usePanelData, LoadState } from "../usePanelData";

export default function ScenePanel() {
  const { api } = useServices();
  const [scene, reload] = usePanelData(() => api.scene(), []);
  return (
    <div className="panel-body scene-panel">
      <LoadState value={scene} what="the 3D scene" />
      {scene.state !== "ready" && <button onClick={reload}>Retry</button>}
      {scene.state === "ready" && <iframe title="3D scene of the drone" src={scene.data.url} className="scene-frame" />}
    </div>
  );
}
