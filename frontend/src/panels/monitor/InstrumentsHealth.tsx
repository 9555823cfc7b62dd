import { formatClock, type InstrumentHealth } from "../../core/instrumentHealth";

/** One row per plug-and-play instrument (core/instrumentHealth.ts): state, last
 * value time, lines ok and bad, reconnects; Modbus timeouts and exceptions when
 * any. A closed, silent or garbage-only instrument is flagged. */
export function InstrumentsHealth({ sensors }: { sensors: InstrumentHealth[] }) {
  if (sensors.length === 0) return null;
  const modbus = sensors.some((s) => s.timeouts || s.exceptions);
  return (
    <table className="instruments-health" aria-label="Instruments' health">
      <thead><tr>
        <th>Instrument</th><th>State</th><th>Last value</th><th>Lines ok</th><th>Lines bad</th><th>Reconnects</th>
        {modbus && <><th>Timeouts</th><th>Exceptions</th></>}
      </tr></thead>
      <tbody>
        {sensors.map((s) => (
          <tr key={s.name} data-sensor={s.name} className={s.alert ? "behind" : undefined}>
            <td>{s.name}</td>
            <td>{s.alert ? <strong role="alert" title={s.alert}>{s.state}</strong> : s.state}</td>
            <td>{s.lastValueMs === null ? "none yet" : formatClock(s.lastValueMs)}</td>
            <td>{s.linesOk}</td><td>{s.linesBad}</td><td>{s.reconnects}</td>
            {modbus && <><td>{s.timeouts}</td><td>{s.exceptions}</td></>}
          </tr>
        ))}
      </tbody>
    </table>
  );
}
