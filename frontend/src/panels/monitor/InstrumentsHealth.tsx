import { formatClock, type InstrumentHealth } from "../../core/instrumentHealth";

/** The plug-and-play instruments (core/instrumentHealth.ts) as one more item
 * of the link status line — how many, in which state, and any flagged one
 * (closed, silent, garbage only) as an alert — that opens on a table, one row
 * per instrument: state, last value time, lines ok and bad, reconnects; Modbus
 * timeouts and exceptions, and fields of no-fix NMEA sentences, when any. Closed by default, so the charts keep
 * their place. */
export function InstrumentsHealth({ sensors }: { sensors: InstrumentHealth[] }) {
  if (sensors.length === 0) return null;
  const modbus = sensors.some((s) => s.timeouts || s.exceptions);
  const noFix = sensors.some((s) => s.noFix);
  const states = ["open", "silent", "closed", "unknown"]
    .map((st) => [st, sensors.filter((s) => s.state === st).length] as const)
    .filter(([, n]) => n > 0).map(([st, n]) => `${n} ${st}`).join(", ");
  const flagged = sensors.filter((s) => s.alert);
  return (
    <details className="instruments-health">
      <summary>
        {" "}· Instruments: {sensors.length} ({states})
        {flagged.length > 0 && <strong className="behind" role="alert">
          {" "}· {flagged.map((s) => `${s.name}: ${s.alert}`).join("; ")}
        </strong>}
      </summary>
      <table aria-label="Instruments' health">
        <thead><tr>
          <th>Instrument</th><th>State</th><th>Last value</th><th>Lines ok</th><th>Lines bad</th><th>Reconnects</th>
          {modbus && <><th>Timeouts</th><th>Exceptions</th></>}
          {noFix && <th>No fix</th>}
        </tr></thead>
        <tbody>
          {sensors.map((s) => (
            <tr key={s.name} data-sensor={s.name} className={s.alert ? "behind" : undefined}>
              <td>{s.name}</td>
              <td>{s.alert ? <strong title={s.alert}>{s.state}</strong> : s.state}</td>
              <td>{s.lastValueMs === null ? "none yet" : formatClock(s.lastValueMs)}</td>
              <td>{s.linesOk}</td><td>{s.linesBad}</td><td>{s.reconnects}</td>
              {modbus && <><td>{s.timeouts}</td><td>{s.exceptions}</td></>}
              {noFix && <td>{s.noFix}</td>}
            </tr>
          ))}
        </tbody>
      </table>
    </details>
  );
}
