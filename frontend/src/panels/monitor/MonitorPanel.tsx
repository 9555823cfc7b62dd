/**
 * Monitor: live charts of the chosen subscriptions (values over the drone's
 * shared stream, app/useDroneStream), link status (RTT, measured against
 * planned bytes/s, time since the last frame), and dynamic subscriptions
 * (scientist) answered ACCEPTED or NOT_AVAILABLE.
 *
 * Charts: several subscriptions per chart, units on the axes, one time
 * window for all (follow live, or zoom by dragging / the buttons and pan),
 * a cursor shared across charts. What is charted, and each chart's history,
 * survive leaving the panel and redeploys (the stream is the workbench's).
 * Missing windows break a chart's line; "Fill gaps" on a chart (its
 * subscriptions) or for the drone (all of them) backfills them from the
 * drone's archive, and the backfilled values appear in place, marked.
 */
import { useDroneName } from "../../app/fleetFocus";
import { useEffect, useState } from "react";
import { fixed, localTime } from "../../core/numberFormat";
import { AggregationValues } from "../../core/model.gen";
import { AGGREGATION } from "../../core/contracts.gen";
import { findTopicByName, listTopics } from "../../core/query";
import { subscriptionLabel, topicLabel } from "../../core/topicLabel";
import { formatRate } from "../../core/plan";
import { canEdit, canFillGaps, canRehearse } from "../../core/roles";
import { formatAge } from "../../core/linkHealth";
import { DEFAULT_WINDOW, panRange, unitLabel, visibleRange, zoomRange, type ViewWindow } from "../../core/chartData";
import { useEditor, useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { useLinkHealth } from "../../app/useLinkHealth";
import type { DynamicReply } from "../../api/types";
import { LiveChart } from "./LiveChart";
import { keepSubscribed, useChartLayout } from "./useChartLayout";
import { ArchiveSpaceNote } from "./ArchiveSpaceNote";
import { FillGaps } from "./FillGaps";
import { Rehearsal } from "./Rehearsal";
import { RadioLine } from "./RadioLine";
import { InstrumentsHealth } from "./InstrumentsHealth";
import { SupervisorNote } from "./SupervisorNote";
import { ActiveAlerts } from "./ActiveAlerts";
import { useAlerts } from "../../app/useAlerts";
import { alertTimes } from "../../core/alerts";

export default function MonitorPanel() {
  const model = useModel();
  const role = useEditor((s) => s.wb.role);
  const { api } = useServices();
  const drone = useDroneName();
  const health = useLinkHealth();
  const { source, state, link } = health.stream;
  const subscribers = model.subscribers.filter((s) => s.topic);
  const layout = useChartLayout(drone, subscribers.slice(0, 4).map((s) => s.name));
  const { charts, win, dynamic } = layout.state;
  const [replies, setReplies] = useState<Array<{ label: string; reply: DynamicReply }>>([]);
  const topics = listTopics(model);
  const [dyn, setDyn] = useState<{ topic: string; period_s: string; aggregation: string }>({ topic: "", period_s: "1.0", aggregation: AGGREGATION.AVERAGE });
  const watched = charts.flat();
  const watchedKey = watched.join(",");
  useEffect(() => { keepSubscribed(source, watchedKey ? watchedKey.split(",") : []); }, [source, watchedKey]);

  const { alerts } = useAlerts();
  const describe = (name: string) => {
    const s = model.subscribers.find((x) => x.name === name);
    const d = dynamic[name];
    const topic = s?.topic ?? d?.topic ?? "";
    const aggregation = s?.aggregation ?? d?.aggregation;
    const unit = unitLabel(findTopicByName(model, topic)?.variable.unit, aggregation);
    const label = s ? subscriptionLabel(model, s) : d ? `${subscriptionLabel(model, { ...d, periodS: d.period_s })} (dynamic)` : "(not in the model)";
    const period = Number(s ? s.periodS : d ? d.period_s : NaN);
    const marks = alertTimes(alerts, name);
    return { channel: name, label, unit, ...(Number.isFinite(period) && period > 0 ? { periodS: period } : {}), ...(marks.length ? { alerts: marks } : {}) };
  };

  const addDynamic = async (e: React.FormEvent) => {
    e.preventDefault();
    const topic = dyn.topic || topics[0]?.name;
    if (!topic) return;
    const label = subscriptionLabel(model, { topic, aggregation: dyn.aggregation, periodS: dyn.period_s });
    try {
      const reply = await api.addDynamic(drone, { ...dyn, topic });
      setReplies((d) => [{ label, reply }, ...d]);
      if (reply.status === "ACCEPTED" && reply.subscriber) layout.addDynamic(reply.subscriber, { ...dyn, topic });
    } catch (err) {
      setReplies((d) => [{ label, reply: { status: "ERROR", reason: (err as Error).message } }, ...d]);
    }
  };

  // The range every chart shows now (for zoom and pan from the buttons).
  const [clock, setClock] = useState(() => Date.now() / 1000);
  useEffect(() => {
    const t = setInterval(() => setClock(Date.now() / 1000), 1000);
    return () => clearInterval(t);
  }, []);
  const newest = Math.max(...watched.map((c) => source.history(c).at(-1)?.t ?? -Infinity));
  const range = visibleRange(win, Number.isFinite(newest) ? newest : clock);
  const setWin = (w: ViewWindow) => layout.setWindow(w);

  return (
    <div className="panel-body monitor-panel">
      <div className="link-status" role="status" aria-label="Link status">
        <span className={`dot dot-${health.down ? "down" : state}`} data-testid="stream-dot" aria-hidden /> stream {state}
        {health.down && <strong className="error"> · link lost: {health.reason}</strong>}
        {link && <>
          · link <strong>{link.state ?? (link.connected ? "up" : "down")}</strong>
          · RTT {fixed(link.rttMs, 1, " ms")}
          · measured {link.measuredBytesPerS === null ? "—" : formatRate(link.measuredBytesPerS)}
          {" "}vs planned {link.plannedBytesPerS === null ? "—" : formatRate(link.plannedBytesPerS)}
          {link.radio && <RadioLine radio={link.radio} />}
          {health.sinceLastFrameS !== null && <> · last frame {formatAge(health.sinceLastFrameS)} ago</>}
          {link.archive && <ArchiveSpaceNote space={link.archive} />}
          {link.behind && <strong className="behind" role="alert">
            {" "}· base station behind the link{link.lagS != null && ` by ${fixed(link.lagS, 1, " s")}`}
          </strong>}
        </>}
        {link?.gaveUp && <SupervisorNote stop={link.gaveUp} />}
        {!link && state === "open" && " · waiting for the drone's status…"}
        {link?.sensors && <InstrumentsHealth sensors={link.sensors} />}
        {link?.onboard?.map((l) => l.ok
          ? <span key={l.process} data-testid={`onboard-${l.process}`}> · last deploy, {l.process}: {l.text}</span>
          : <strong key={l.process} className="behind" role="alert" data-testid={`onboard-${l.process}`}>
            {" "}· last deploy, {l.process}: {l.text}
          </strong>)}
      </div>
      <ActiveAlerts role={role} />
      <div className="monitor-grid">
        <aside className="watch-list" aria-label="Subscriptions to watch">
          <h3>Watch</h3>
          {subscribers.length === 0 && <p className="muted">No subscription in the model.</p>}
          {subscribers.map((s) => (
            <label key={s.name}><input type="checkbox" checked={watched.includes(s.name)} onChange={() => layout.toggle(s.name)} />
              {s.name} <span className="muted">{subscriptionLabel(model, s)}</span></label>
          ))}
          {Object.entries(dynamic).map(([name, d]) => (
            <label key={name}><input type="checkbox" checked={watched.includes(name)} onChange={() => layout.toggle(name)} />
              {name} <span className="muted">{subscriptionLabel(model, { ...d, periodS: d.period_s })} (dynamic)</span></label>
          ))}
          {canRehearse(role) && <Rehearsal drone={drone} />}
          {canFillGaps(role) && <FillGaps drone={drone} source={source} scope={`drone ${drone}`}
            subscribers={subscribers.map((s) => s.name)} />}
          {canEdit(role, "subscriber") && (
            <form onSubmit={addDynamic} className="dynamic-form" aria-label="Dynamic subscription">
              <h3>Dynamic subscription</h3>
              <select aria-label="Topic" value={dyn.topic || topics[0]?.name || ""} onChange={(e) => setDyn({ ...dyn, topic: e.target.value })}>
                {topics.map((t) => <option key={t.id} value={t.name}>{topicLabel(model, t.name)}</option>)}
              </select>
              <input aria-label="Period (s)" value={dyn.period_s} onChange={(e) => setDyn({ ...dyn, period_s: e.target.value })} size={5} />
              <select aria-label="Aggregation" value={dyn.aggregation} onChange={(e) => setDyn({ ...dyn, aggregation: e.target.value })}>
                {AggregationValues.filter((a) => a !== AGGREGATION.ON_CHANGE && a !== AGGREGATION.THRESHOLD).map((a) => (a === AGGREGATION.PERCENTILE ? `${a}(95)` : a)).map((a) => <option key={a}>{a}</option>)}
              </select>
              <button type="submit">Ask the drone</button>
              <ul className="dynamic-replies">
                {replies.map((d, i) => (
                  <li key={i} className={d.reply.status === "ACCEPTED" ? "status-ok" : "error"}>
                    {d.label}: <strong>{d.reply.status}</strong>{d.reply.reason ? ` — ${d.reply.reason}` : ""}{d.reply.subscriber ? ` (${d.reply.subscriber})` : ""}
                  </li>
                ))}
              </ul>
            </form>
          )}
        </aside>
        <div>
          <div className="chart-tools" role="toolbar" aria-label="Time window">
            <button onClick={() => setWin(zoomRange(range, 0.5))}>Zoom in on time</button>
            <button onClick={() => setWin(zoomRange(range, 2))}>Zoom out in time</button>
            <button onClick={() => setWin(panRange(range, -0.5))}>← Earlier</button>
            <button onClick={() => setWin(panRange(range, 0.5))}>Later →</button>
            <button aria-pressed={win.follow} onClick={() => setWin(DEFAULT_WINDOW)}>Follow live</button>
            <span className="muted" data-testid="time-window">
              {win.follow ? `following, last ${fixed(win.spanS, 0)} s` : `${localTime(range[0])} – ${localTime(range[1])} (${fixed(range[1] - range[0], 1)} s)`}
              {" "}· drag across a chart to zoom
            </span>
          </div>
          <div className="charts">
            {charts.length === 0 && <p className="muted">Tick subscriptions to chart them.</p>}
            {charts.map((chart, i) => (
              <LiveChart key={chart.join("+")} source={source} series={chart.map(describe)} window={win}
                onZoom={(from, to) => setWin({ follow: false, from, to })}
                addable={watched.filter((c) => !chart.includes(c))}
                onAdd={(c) => layout.moveTo(c, i)} onRemove={(c) => layout.split(c)}
                tools={canFillGaps(role) && <FillGaps drone={drone} source={source} subscribers={chart.filter((c) => !(c in dynamic))} scope={chart.join(", ")} compact />} />
            ))}
          </div>
        </div>
      </div>
    </div>
  );
}
