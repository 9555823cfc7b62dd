/**
 * Fleet: every drone of the project (a campaign's vehicles, or its one
 * drone) on one map, with its link state, serving station, last window and
 * instruments' health (its status, polled from the backend's /drones); a
 * deploy to the drones ticked, at once, with each one's acknowledgement and a
 * rollback per drone (the last other revision it ran); a live subscription
 * to one variable of every drone in one step. "Monitor" shows one drone in
 * the per-drone panels (Monitor, Map), as for a one-drone project.
 *
 * The map places each drone at its last fix, from the project's position
 * subscriptions (core/track) over that drone's own live stream.
 */
import { useEffect, useRef, useState } from "react";
import { AGGREGATION } from "../../core/contracts.gen";
import { AggregationValues } from "../../core/model.gen";
import { positionSubscribers } from "../../core/track";
import { listTopics } from "../../core/query";
import { canDeploy, canFillGaps, type Role } from "../../core/roles";
import { useEditor, useModel } from "../../editor/useEditor";
import { useServices } from "../../app/services";
import { useDroneStream } from "../../app/useDroneStream";
import { focusDrone, useDroneName } from "../../app/fleetFocus";
import type { Deployment, Fleet, FleetSubscription } from "../../api/types";
import { drawFleet, type Fix } from "./fleetMap";
import { droneRow, fleetVariables, rollbackRevision, type DroneRow } from "./fleetRows";

const POLL_MS = 2000;

/** One drone's last fix from its own stream, handed up. */
function DroneFix({ drone, lat, lon, onFix }: { drone: string; lat: string; lon: string; onFix: (f: Fix) => void }) {
  const { source } = useDroneStream(drone);
  useEffect(() => {
    const read = () => {
      const a = source.history(lat), b = source.history(lon);
      if (a.length && b.length) onFix({ name: drone, lat: a[a.length - 1].value, lon: b[b.length - 1].value });
    };
    read();
    const offs = [source.subscribe(lat, read), source.subscribe(lon, read)];
    return () => offs.forEach((o) => o());
  }, [source, drone, lat, lon, onFix]);
  return null;
}

function FleetMap({ names, links }: { names: string[]; links: Record<string, string | null> }) {
  const model = useModel();
  const { lat, lon } = positionSubscribers(model);
  const [fixes, setFixes] = useState<Record<string, Fix>>({});
  const canvas = useRef<HTMLCanvasElement>(null);
  const onFix = useRef((f: Fix) => setFixes((all) => (all[f.name]?.lat === f.lat && all[f.name]?.lon === f.lon ? all : { ...all, [f.name]: f }))).current;
  const shown = names.filter((n) => fixes[n]).map((n) => fixes[n]);
  useEffect(() => {
    if (!canvas.current) return;
    const placed = drawFleet(canvas.current, shown, links);
    canvas.current.dataset.placed = JSON.stringify(placed.map((p) => [p.name, Math.round(p.x), Math.round(p.y)]));
  }, [shown, links]);
  return (
    <div className="fleet-map">
      {lat && lon && names.map((n) => <DroneFix key={n} drone={n} lat={lat} lon={lon} onFix={onFix} />)}
      <canvas ref={canvas} className="map-canvas" role="img" data-testid="fleet-canvas" data-drones={shown.length}
        aria-label={`Fleet map: ${shown.length} of ${names.length} drones placed`} />
      <p className="muted" role="status" data-testid="fleet-fixes">
        {!lat || !lon ? "No subscription delivers a latitude and a longitude: subscribe to them to place the drones."
          : `${shown.length} of ${names.length} drones placed at their last fix (${lat}, ${lon}); north up.`}
      </p>
    </div>
  );
}

function age(s: number | null): string {
  return s === null ? "—" : s < 1 ? "now" : `${s.toFixed(0)} s before its status`;
}

interface RowProps {
  row: DroneRow; ticked: boolean; onTick: (on: boolean) => void; rollback: number | null;
  allowed: boolean; busy: boolean; onRollback: () => void; shown: boolean;
}

function Row({ row, ticked, onTick, rollback, allowed, busy, onRollback, shown }: RowProps) {
  const d = row.deployed;
  return (
    <tr data-testid={`fleet-row-${row.name}`}>
      <td><label><input type="checkbox" checked={ticked} onChange={(e) => onTick(e.target.checked)} aria-label={`Deploy to ${row.name}`} /> {row.name}</label>
        {row.description && <span className="muted"> {row.description}</span>}</td>
      <td data-testid="fleet-link">{row.link ?? "not reporting"}</td>
      <td data-testid="fleet-station">{row.station ?? "—"}</td>
      <td>{age(row.lastWindowAgeS)}</td>
      <td title={row.instrumentAlerts.join("; ")}>{row.instruments}{row.instrumentAlerts.length > 0 && <span className="error"> ({row.instrumentAlerts.join("; ")})</span>}</td>
      <td data-testid="fleet-deployed">{d ? `r${d.revision} ${d.status}${d.error ? `: ${d.error}` : ""}` : "—"}</td>
      <td>
        <button type="button" disabled={!allowed || busy || rollback === null} onClick={onRollback}
          title={rollback === null ? "no earlier revision ran on this drone" : `deploy revision ${rollback} to ${row.name} alone`}>
          Roll back{rollback !== null ? ` to r${rollback}` : ""}
        </button>{" "}
        <button type="button" aria-pressed={shown} onClick={() => focusDrone(row.name)}>Monitor</button>
      </td>
    </tr>
  );
}

function Results({ records }: { records: Deployment[] }) {
  return (
    <ul data-testid="fleet-deploy-results">
      {records.map((r) => (
        <li key={r.id} className={r.status === "acked" ? "" : "error"} data-testid={`fleet-ack-${r.drone}`}>
          {r.drone}: revision {r.revision} {r.status}{r.error ? ` (${r.error})` : ""}
        </li>
      ))}
    </ul>
  );
}

function Subscribe({ pid, role }: { pid: number; role: Role }) {
  const { api } = useServices();
  const variables = fleetVariables(listTopics(useModel()).map((t) => t.name));
  const [form, setForm] = useState({ variable: variables[0] ?? "", period_s: "1.0", aggregation: AGGREGATION.AVERAGE as string, subscriber: "" });
  const [answers, setAnswers] = useState<FleetSubscription[]>([]);
  const [error, setError] = useState<string | null>(null);
  const send = async () => {
    setError(null);
    try {
      setAnswers(await api.subscribeFleet(pid, { ...form, subscriber: form.subscriber || undefined }));
    } catch (e) { setError(e instanceof Error ? e.message : String(e)); }
  };
  const set = (k: keyof typeof form) => (e: { target: { value: string } }) => setForm({ ...form, [k]: e.target.value });
  return (
    <section aria-label="Subscribe on every drone">
      <h4>One variable of every drone</h4>
      <select aria-label="Variable" value={form.variable} onChange={set("variable")}>
        {variables.map((v) => <option key={v} value={v}>{v}</option>)}
      </select>{" "}
      <input aria-label="Period (s)" value={form.period_s} onChange={set("period_s")} size={6} />{" "}
      <select aria-label="Aggregation" value={form.aggregation} onChange={set("aggregation")}>
        {AggregationValues.map((a) => <option key={a} value={a}>{a}</option>)}
      </select>{" "}
      <input aria-label="Subscription name" placeholder="name (optional)" value={form.subscriber} onChange={set("subscriber")} />{" "}
      <button type="button" disabled={!canFillGaps(role) || !form.variable} onClick={() => { void send(); }}>Subscribe on every drone</button>
      {error && <p className="error" role="alert">{error}</p>}
      <ul data-testid="fleet-subscribe-results">
        {answers.map((a) => (
          <li key={a.drone} className={a.status === "ACCEPTED" ? "" : "error"} data-testid={`fleet-sub-${a.drone}`}>
            {a.drone}: {a.topic} {a.status}{a.key ? ` on ${a.key}` : ""}{a.reason ? ` (${a.reason})` : ""}
          </li>
        ))}
      </ul>
    </section>
  );
}

export default function FleetPanel() {
  const { api } = useServices();
  const project = useEditor((s) => s.project);
  const role = useEditor((s) => s.wb.role);
  const head = useEditor((s) => s.savedRevision);
  const shown = useDroneName();
  const pid = project?.id ?? 0;
  const [fleet, setFleet] = useState<Fleet | null>(null);
  const [history, setHistory] = useState<Deployment[]>([]);
  const [untick, setUntick] = useState<Set<string>>(new Set());
  const [busy, setBusy] = useState(false);
  const [records, setRecords] = useState<Deployment[]>([]);
  const [error, setError] = useState<string | null>(null);
  const [tick, setTick] = useState(0);
  useEffect(() => {
    if (!pid) return;
    let live = true;
    const load = () => {
      api.fleet(pid).then((f) => { if (live) setFleet(f); }, (e: unknown) => { if (live) setError(e instanceof Error ? e.message : String(e)); });
      api.listDeployments(pid).then((h) => { if (live) setHistory(h); }, () => undefined);
    };
    load();
    const timer = window.setInterval(load, POLL_MS);
    return () => { live = false; window.clearInterval(timer); };
  }, [api, pid, head, tick]);

  if (!project) return <div className="panel-body"><p className="muted">Open a project to see its drones.</p></div>;
  const rows = (fleet?.drones ?? []).map(droneRow);
  const names = rows.map((r) => r.name);
  const chosen = names.filter((n) => !untick.has(n));
  const links = Object.fromEntries(rows.map((r) => [r.name, r.link]));
  const deploy = async (drones: string[], revision?: number) => {
    setBusy(true); setError(null);
    try { setRecords(await api.deployFleet(pid, drones, revision)); } catch (e) { setError(e instanceof Error ? e.message : String(e)); }
    setBusy(false); setTick((n) => n + 1);
  };
  const allowed = canDeploy(role);
  return (
    <div className="panel-body fleet-panel">
      <p>{fleet?.campaign ? <>Campaign <strong>{fleet.campaign}</strong>: </> : null}{names.length} drone{names.length === 1 ? "" : "s"}
        {fleet && Object.entries(fleet.channels).map(([c, m]) => <span key={c} className="muted">; channel {c}: {m.join(", ")}</span>)}</p>
      <FleetMap names={names} links={links} />
      <table className="fleet-table">
        <thead><tr><th>Drone</th><th>Link</th><th>Station</th><th>Last window</th><th>Instruments</th><th>Deployed</th><th /></tr></thead>
        <tbody>{rows.map((r) => (
          <Row key={r.name} row={r} ticked={!untick.has(r.name)} shown={r.name === shown} allowed={allowed} busy={busy}
            rollback={rollbackRevision(r.name, history)}
            onTick={(on) => setUntick((s) => { const n = new Set(s); if (on) n.delete(r.name); else n.add(r.name); return n; })}
            onRollback={() => { const rev = rollbackRevision(r.name, history); if (rev !== null) void deploy([r.name], rev); }} />
        ))}</tbody>
      </table>
      <button type="button" disabled={!allowed || busy || !chosen.length || !head} onClick={() => { void deploy(chosen); }}>
        {busy ? "Deploying…" : `Deploy revision ${head ?? "—"} to ${chosen.length} drone${chosen.length === 1 ? "" : "s"}`}
      </button>
      {!allowed && <span className="muted"> Deploying needs the operator role.</span>}
      {error && <p className="error" role="alert">{error}</p>}
      <Results records={records} />
      <Subscribe pid={pid} role={role} />
    </div>
  );
}
