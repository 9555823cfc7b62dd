/**
 * One hyperperiod of the schedule: a tick per message (slot), its streams in
 * the tooltip and the list below. Zoom with the buttons or the wheel; drag
 * the slider to pan. Long hyperperiods with many slots stay readable zoomed.
 */
import { useMemo, useState } from "react";
import { timeline, zoomWindow, type PlanJson } from "../../core/plan";
import { axisTicks, layoutTicks } from "../../core/timelineScale";

export function Timeline({ plan }: { plan: PlanJson }) {
  const hyper = Number(plan.hyperperiod_s);
  const [zoom, setZoom] = useState(1);
  const [center, setCenter] = useState(hyper / 2);
  const [from, to] = zoomWindow(hyper, center, hyper / zoom);
  const marks = useMemo(() => timeline(plan, from, to), [plan, from, to]);
  const [picked, setPicked] = useState<number | null>(null);
  const pickedMark = marks.find((m) => m.slot === picked) ?? marks[0];
  // Ticks never overlap: narrower than the typical gap, and messages closer than that stacked in lanes.
  const { width, lanes, lane } = useMemo(() => layoutTicks(marks.map((m) => m.x)), [marks]);
  const laneH = 36 / lanes;

  return (
    <div className="timeline">
      <div className="timeline-controls">
        <button aria-label="Zoom in" onClick={() => setZoom((z) => Math.min(z * 2, 1e6))}>+</button>
        <button aria-label="Zoom out" onClick={() => setZoom((z) => Math.max(z / 2, 1))}>−</button>
        <button onClick={() => { setZoom(1); setCenter(hyper / 2); }}>All</button>
        <input type="range" aria-label="Pan" min={0} max={hyper} step={hyper / 1000} value={center}
          disabled={zoom === 1} onChange={(e) => setCenter(Number(e.target.value))} />
        <span className="muted">{from.toFixed(3)} s – {to.toFixed(3)} s · {marks.length} message(s) shown</span>
      </div>
      <svg className="timeline-svg" viewBox="0 0 1000 60" preserveAspectRatio="none" role="img"
        aria-label={`Schedule of one hyperperiod: ${plan.messages_per_hyperperiod} messages`}
        onWheel={(e) => setZoom((z) => Math.min(Math.max(e.deltaY < 0 ? z * 1.25 : z / 1.25, 1), 1e6))}>
        <line x1={0} y1={40} x2={1000} y2={40} className="timeline-axis" />
        {marks.map((m, i) => (
          <g key={m.slot} onClick={() => setPicked(m.slot)} className={m.slot === pickedMark?.slot ? "tick picked" : "tick"}>
            <title>{`slot ${m.slot} at ${m.t} s: ${m.streams.join(", ")}`}</title>
            {lanes === 1
              ? <rect x={m.x * (1000 - width)} y={40 - Math.min(8 + 6 * m.streams.length, 38)} width={width} height={Math.min(8 + 6 * m.streams.length, 38)} data-testid="schedule-tick" />
              : <rect x={m.x * (1000 - width)} y={40 - (lane[i] + 1) * laneH} width={width} height={Math.max(laneH - 1, 1)} data-testid="schedule-tick" />}
          </g>
        ))}
      </svg>
      <div className="timeline-scale" aria-label="Time within the hyperperiod">
        {axisTicks(from, to).map((t) => <span key={t.label} style={{ left: `${t.x * 100}%` }}>{t.label}</span>)}
      </div>
      {pickedMark && (
        <p className="timeline-detail">
          Message {pickedMark.slot} at {pickedMark.t} s carries {pickedMark.streams.length} stream(s): {pickedMark.streams.join(", ")}
        </p>
      )}
      {plan.schedule.slots_truncated && <p className="muted">Only the first {plan.schedule.slots_listed} messages are listed by the planner.</p>}
    </div>
  );
}
