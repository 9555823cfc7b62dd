/**
 * The declared radio's share of the plan (the planner's `radio`: air time,
 * duty-cycle share, energy per hour, battery share), its refusal naming the
 * subscriptions that cost most, and the nearest plans that fit, each one
 * planned again by the planner (figures from the planning engine only).
 */
import { formatRate, type PlanJson } from "../../core/plan";

type Radio = NonNullable<PlanJson["radio"]>;

const percent = (share: number) => `${(share * 100).toFixed(share < 0.1 ? 2 : 1)} %`;

/** How sure a figure is (docs/planning.md, "Bounds and estimates"): with declared
 * resolutions the planner sizes quantised values at their declared range ("at most")
 * or assumes small deltas ("about"); the duty-cycle share is then the bound's. */
type Figures = { figures?: "exact" | "upper_bound" | "estimate"; air_time_bound_s_per_hour?: number | null };
export const hedge = (f: Figures) => (f.figures === "upper_bound" ? "at most " : f.figures === "estimate" ? "about " : "");
const FIGURES_TITLE = {
  upper_bound: "Every quantised value sized at its declared range: a smaller signal costs less.",
  estimate: "Quantised values assumed to change little between windows; the duty-cycle share is the bound's (every change as wide as the declared range).",
  exact: undefined,
} as const;
const CALIBRATED_TITLE = "Quantised values sized from a test flight's archive (their mean sizes in its windows); the duty-cycle share is the bound's when the variables declare ranges.";

export function AirTimeView({ radio, onSelect }: { radio: Radio; onSelect: (subscriber: string) => void }) {
  return (
    <section className="air-time" aria-label="Radio air time and energy">
      <div className="plan-summary">
        <div className="figure"><span>Radio</span><strong data-testid="radio-kind">{radio.kind}</strong></div>
        <div className="figure" title={radio.calibrated_from ? CALIBRATED_TITLE : FIGURES_TITLE[radio.figures ?? "exact"]}><span>Air time / hour</span>
          <strong data-testid="air-time">{hedge(radio)}{radio.air_time_s_per_hour.toFixed(1)} s</strong>
          {radio.air_time_bound_s_per_hour != null && (
            <span data-testid="air-time-bound">at most {radio.air_time_bound_s_per_hour.toFixed(1)} s</span>
          )}</div>
        {radio.duty_share !== null && radio.duty_cycle !== null && (
          <div className="figure"><span>{radio.air_time_bound_s_per_hour != null ? "At most, of" : "Share of"} the {percent(radio.duty_cycle)} duty cycle</span>
            <strong data-testid="duty-share">{percent(radio.duty_share)}</strong></div>
        )}
        <div className="figure"><span>Energy / hour</span><strong data-testid="energy">{hedge(radio)}{radio.energy_j_per_hour.toFixed(1)} J</strong></div>
        {radio.battery_share_per_hour !== null && radio.battery_wh !== null && (
          <div className="figure"><span>Of the {radio.battery_wh} Wh battery / hour</span>
            <strong data-testid="battery-share">{percent(radio.battery_share_per_hour)}</strong></div>
        )}
        <div className="figure muted"><span>Packets / hour</span><strong>{radio.packets_per_hour.toFixed(0)}</strong></div>
      </div>
      {radio.calibrated_from && (
        <p className="muted" data-testid="calibrated-from">
          Quantised values sized from {radio.calibrated_from} ({radio.calibration?.streams.length ?? 0} streams
          {radio.calibration?.not_calibrated.length ? `; not in it: ${radio.calibration.not_calibrated.join(", ")}` : ""})
        </p>
      )}
      {radio.error && (
        <div className="infeasible" role="alert" data-testid="radio-error">
          <strong>Refused by the radio</strong> {radio.error}
          <div>{radio.costs.slice(0, 5).map((c) => (
            <button key={c.subscription} className="link chip" onClick={() => onSelect(c.subscription)}>
              {c.subscription} ({c.air_time_s_per_hour.toFixed(1)} s/h)
            </button>
          ))}</div>
        </div>
      )}
      {radio.proposals.length > 0 && (
        <table className="buffer-table" aria-label="Nearest plans that fit">
          <thead><tr><th>Nearest plan that fits</th><th>Delay</th><th>Link</th><th>Air time / h</th><th>Energy / h</th></tr></thead>
          <tbody>
            {radio.proposals.map((p) => (
              <tr key={p.change} data-testid="proposal">
                <td>{p.change}</td><td>{p.max_delay_s.toFixed(1)} s</td><td>{formatRate(p.bytes_per_s)}</td>
                <td>{hedge(p)}{p.air_time_s_per_hour.toFixed(1)} s ({p.air_time_bound_s_per_hour != null ? "at most " : ""}{percent(p.duty_share)})</td>
                <td>{hedge(p)}{p.energy_j_per_hour.toFixed(1)} J</td>
              </tr>
            ))}
          </tbody>
        </table>
      )}
    </section>
  );
}
