/**
 * Listens for saves of the open project on the drone's stream WebSocket
 * (`{"op": "watch"}`, backend project_events.py) and keeps the newest in the
 * store, where RemoteSaveNotice shows it.
 */
import { useEffect } from "react";
import { useEditor, useEditorStore } from "../editor/useEditor";
import { useServices } from "./services";

export function useProjectEvents(): void {
  const { openStream } = useServices();
  const store = useEditorStore();
  const projectId = useEditor((s) => s.project?.id ?? null);
  const drone = useEditor((s) => s.savedModel?.drone.name ?? "");
  useEffect(() => {
    if (projectId === null || !/^[A-Za-z_][A-Za-z0-9_]*$/.test(drone)) return;
    const source = openStream(drone);
    const stop = source.watchProject?.(projectId, (e) => {
      const prev = store.getState().remoteSave;
      if (!prev || e.revision > prev.revision) store.patch({ remoteSave: e });
    });
    return () => { stop?.(); source.close(); };
  }, [openStream, store, projectId, drone]);
}
