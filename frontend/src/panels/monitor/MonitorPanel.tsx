/**
 * Monitor: live charts of the chosen subscriptions (values over the drone's
 * stream WebSocket), link status (RTT, measured against planned bytes/s), and
 * dynamic subscriptions (scientist) answered ACCEPTED or NOT_AVAILABLE.
 */
import { useEffect, useMemo, useState } from "react";
import { AggregationValues } from "../../core/model.gen";
import { listTopics } from "../../core/query";
import { formatRate } from "../../core/plan";
import { canEdit } from "../../core/roles";
import { useEditor, useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import type { ConnectionState, DataSource, LinkStatus } from "../../dataSources/types";
import type { DynamicReply } from "../../api/types";
import { LiveChart } from "./LiveChart";
import { RadioLine } from "./RadioLine";

function useStream(drone: string): { source: DataSource; state: ConnectionState; link: LinkStatus | null } {
  const { openStream } = useServices();
  const source = useMemo(() => openStream(drone), [openStream, drone]);
  const [state, setState] = useState<ConnectionState>(source.state);
  const [link, setLink] = useState<LinkStatus | null>(null);
  useEffect(() => {
    const a = source.onStateChange(setState);
    const b = source.onLinkStatus(setLink);
    setState(source.state);
    return () => { a(); b(); source.close(); };
  }, [source]);
  return { source, state, link };
}

export default function MonitorPanel() {
  const model = useModel();
  const role = useEditor((s) => s.wb.role);
  const { api } = useServices();
  const drone = model.drone.name;
  const { source, state, link } = useStream(drone);
  const subscribers = model.subscribers.filter((s) => s.topic);
  const [watched, setWatched] = useState<string[]>(() => subscribers.slice(0, 4).map((s) => s.name));
  const [dynamic, setDynamic] = useState<Array<{ label: string; reply: DynamicReply }>>([]);
  const topics = listTopics(model);
  const [dyn, setDyn] = useState({ topic: "", period_s: "1.0", aggregation: "AVERAGE" });

  const toggle = (name: string) => setWatched((w) => (w.includes(name) ? w.filter((x) => x !== name) : [...w, name]));

  const addDynamic = async (e: React.FormEvent) => {
    e.preventDefault();
    const topic = dyn.topic || topics[0]?.name;
    if (!topic) return;
    const label = `${topic} ${dyn.aggregation} every ${dyn.period_s} s`;
    try {
      const reply = await api.addDynamic(drone, { ...dyn, topic });
      setDynamic((d) => [{ label, reply }, ...d]);
      if (reply.status === "ACCEPTED" && reply.subscriber) setWatched((w) => [...w, reply.subscriber!]);
    } catch (err) {
      setDynamic((d) => [{ label, reply: { status: "ERROR", reason: (err as Error).message } }, ...d]);
    }
  };

  return (
    <div className="panel-body monitor-panel">
      <div className="link-status" role="status" aria-label="Link status">
        <span className={`dot dot-${state}`} aria-hidden /> stream {state}
        {link && <>
          · link <strong>{link.state ?? (link.connected ? "up" : "down")}</strong>
          · RTT {link.rttMs === null ? "—" : `${link.rttMs.toFixed(1)} ms`}
          · measured {link.measuredBytesPerS === null ? "—" : formatRate(link.measuredBytesPerS)}
          {" "}vs planned {link.plannedBytesPerS === null ? "—" : formatRate(link.plannedBytesPerS)}
          {link.radio && <RadioLine radio={link.radio} />}
          {link.lastFrameAgeS !== null && <> · last frame {link.lastFrameAgeS.toFixed(1)} s ago</>}
          {link.behind && <strong className="behind" role="alert">
            {" "}· base station behind the link{link.lagS != null && ` by ${link.lagS.toFixed(1)} s`}
          </strong>}
        </>}
        {!link && state === "open" && " · waiting for the drone's status…"}
      </div>
      <div className="monitor-grid">
        <aside className="watch-list" aria-label="Subscriptions to watch">
          <h3>Watch</h3>
          {subscribers.length === 0 && <p className="muted">No subscription in the model.</p>}
          {subscribers.map((s) => (
            <label key={s.name}><input type="checkbox" checked={watched.includes(s.name)} onChange={() => toggle(s.name)} />
              {s.name} <span className="muted">{s.aggregation} {s.periodS} s</span></label>
          ))}
          {canEdit(role, "subscriber") && (
            <form onSubmit={addDynamic} className="dynamic-form" aria-label="Dynamic subscription">
              <h3>Dynamic subscription</h3>
              <select aria-label="Topic" value={dyn.topic || topics[0]?.name || ""} onChange={(e) => setDyn({ ...dyn, topic: e.target.value })}>
                {topics.map((t) => <option key={t.id}>{t.name}</option>)}
              </select>
              <input aria-label="Period (s)" value={dyn.period_s} onChange={(e) => setDyn({ ...dyn, period_s: e.target.value })} size={5} />
              <select aria-label="Aggregation" value={dyn.aggregation} onChange={(e) => setDyn({ ...dyn, aggregation: e.target.value })}>
                {AggregationValues.map((a) => <option key={a}>{a}</option>)}
              </select>
              <button type="submit">Ask the drone</button>
              <ul className="dynamic-replies">
                {dynamic.map((d, i) => (
                  <li key={i} className={d.reply.status === "ACCEPTED" ? "status-ok" : "error"}>
                    {d.label}: <strong>{d.reply.status}</strong>{d.reply.reason ? ` — ${d.reply.reason}` : ""}{d.reply.subscriber ? ` (${d.reply.subscriber})` : ""}
                  </li>
                ))}
              </ul>
            </form>
          )}
        </aside>
        <div className="charts">
          {watched.length === 0 && <p className="muted">Tick subscriptions to chart them.</p>}
          {watched.map((name) => {
            const s = model.subscribers.find((x) => x.name === name);
            return <LiveChart key={name} source={source} subscriber={name} label={s ? `${s.topic} ${s.aggregation} ${s.periodS} s` : "dynamic"} />;
          })}
        </div>
      </div>
    </div>
  );
}
