/**
 * The backend's viser scene (drone track and attitude), embedded from the
 * backend's own origin (SCENE_PATH, proxied behind the session), so it works
 * from another machine too. A browser without WebGL gets the 2D map instead.
 * Until viser has connected and drawn the scene's own panel, a cover says
 * "Connecting…" over viser's developer controls (sceneCover.ts).
 */
import { useEffect, useRef, useState } from "react";
import { SCENE_PATH } from "../../api/client";
import { useServices } from "../../app/services";
import { usePanelData, LoadState } from "../usePanelData";
import { sceneShowsOnlyItsOwn } from "./sceneCover";

function hasWebGL(): boolean {
  try {
    const c = document.createElement("canvas");
    return !!(c.getContext("webgl2") ?? c.getContext("webgl"));
  } catch {
    return false;
  }
}

/** Whether the framed scene shows only its own (polled every 200 ms until it does; a page not readable counts as shown). */
function useSceneShown(frame: React.RefObject<HTMLIFrameElement | null>, on: boolean): boolean {
  const [shown, setShown] = useState(false);
  useEffect(() => {
    if (!on) return;
    setShown(false);
    const timer = window.setInterval(() => {
      let ok: boolean;
      try { ok = sceneShowsOnlyItsOwn(frame.current?.contentDocument); } catch { ok = true; /* another origin: nothing to read */ }
      if (ok) { setShown(true); window.clearInterval(timer); }
    }, 200);
    return () => window.clearInterval(timer);
  }, [frame, on]);
  return shown;
}

export default function ScenePanel() {
  const { api } = useServices();
  const [scene, reload] = usePanelData(() => api.scene(), []);
  const webgl = hasWebGL();
  const frame = useRef<HTMLIFrameElement>(null);
  const shown = useSceneShown(frame, scene.state === "ready");
  return (
    <div className="panel-body scene-panel">
      <LoadState value={scene} what="the 3D scene" />
      {scene.state !== "ready" && <button onClick={reload}>Retry</button>}
      {!webgl && <p className="warning-banner" role="status">This browser has no WebGL: the 3D view cannot draw here. The Map panel draws the track in 2D.</p>}
      {scene.state === "ready" && (
        <div className="scene-stage">
          <iframe ref={frame} title="3D scene of the drone" src={SCENE_PATH} className="scene-frame" />
          {!shown && <div className="scene-cover" role="status">Connecting to the 3D scene…</div>}
        </div>
      )}
    </div>
  );
}
