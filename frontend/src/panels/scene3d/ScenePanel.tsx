/**
 * The backend's viser scene (drone track and attitude), embedded from the
 * backend's own origin (SCENE_PATH, proxied behind the session), so it works
 * from another machine too. A browser without WebGL gets the 2D map instead.
 */
import { SCENE_PATH } from "../../api/client";
import { useServices } from "../../app/services";
import { usePanelData, LoadState } from "../usePanelData";

function hasWebGL(): boolean {
  try {
    const c = document.createElement("canvas");
    return !!(c.getContext("webgl2") ?? c.getContext("webgl"));
  } catch {
    return false;
  }
}

export default function ScenePanel() {
  const { api } = useServices();
  const [scene, reload] = usePanelData(() => api.scene(), []);
  const webgl = hasWebGL();
  return (
    <div className="panel-body scene-panel">
      <LoadState value={scene} what="the 3D scene" />
      {scene.state !== "ready" && <button onClick={reload}>Retry</button>}
      {!webgl && <p className="warning-banner" role="status">This browser has no WebGL: the 3D view cannot draw here. The Map panel draws the track in 2D.</p>}
      {scene.state === "ready" && <iframe title="3D scene of the drone" src={SCENE_PATH} className="scene-frame" />}
    </div>
  );
}
