/**
 * The base-station records of a drone: one MCAP per mission of every value
 * the SubBroker delivered, live and backfilled (docs/subbroker.md), listed
 * and downloadable beside the drone's own archive.
 */
import { useState } from "react";
import { useServices } from "../../app/services";
import type { ArchiveReplay } from "../../api/types";
import { saveBlob } from "../saveBlob";
import { usePanelData } from "../usePanelData";

export function BaseRecords({ drone, autoplay = false }: { drone: string; autoplay?: boolean }) {
  const { api } = useServices();
  const [files, reload] = usePanelData(() => api.listRecords(drone), [drone]);
  const download = async (name: string) => saveBlob(await api.downloadRecord(drone, name), name);
  const [replay, setReplay] = useState<{ data?: ArchiveReplay; error?: string }>({});
  const startReplay = async (name: string) => {
    try { setReplay({ data: await api.replayRecord(drone, name, autoplay) }); } catch (err) { setReplay({ error: (err as Error).message }); }
  };
  return (
    <section aria-label="Base-station records">
      <h3>Base-station records <button className="link" onClick={reload}>refresh</button></h3>
      {files.state === "ready" ? (
        <table className="history-table" aria-label="Base-station record files">
          <thead><tr><th>File</th><th>Size</th><th>Values</th><th /></tr></thead>
          <tbody>
            {files.data.length === 0 && <tr><td colSpan={4} className="muted">No record yet for {drone}.</td></tr>}
            {files.data.map((f) => (
              <tr key={f.name}>
                <td>{f.name}{f.complete ? "" : " (being written)"}</td>
                <td>{(f.size / 1024).toFixed(1)} KiB</td>
                <td>{f.topics.reduce((n, t) => n + t.messages, 0)}</td>
                <td><button className="link" onClick={() => void download(f.name)}>download</button>{" "}
                  <button className="link" onClick={() => void startReplay(f.name)}>replay in Foxglove</button></td>
              </tr>
            ))}
          </tbody>
        </table>
      ) : <p className="muted">{files.state === "loading" ? "loading…" : "records unavailable"}</p>}
      {replay.data && (
        <p role="status" aria-label="Foxglove replay of a record">
          Replay of {replay.data.file} ({replay.data.messages} values): in Foxglove or Lichtblick,
          Open connection → Foxglove WebSocket → <code>{replay.data.url}</code>
          {replay.data.autoplay && " (plays from the start when the viewer subscribes)"}
        </p>
      )}
      {replay.error && <p className="error" role="alert">{replay.error}</p>}
    </section>
  );
}
