/**
 * The link budget of the declared transport: bytes/s on the wire with that
 * transport's headers, share of the radio's usable bytes/s, the delay each
 * subscription sees, and the planner's error naming the subscriptions that
 * make the plan exceed the budget (figures from the planning engine only).
 */
import { formatRate, TRANSPORT_HEADERS, type LinkBudget } from "../../core/plan";
import { LINK_DELAY_HELP } from "./delayWords";

export function LinkBudgetView({ budget, onSelect }: { budget: LinkBudget; onSelect: (subscriber: string) => void }) {
  const delays = Object.entries(budget.delays_s);
  return (
    <section className="link-budget" aria-label="Link budget">
      <div className="plan-summary">
        <div className="figure"><span>Transport</span><strong data-testid="transport">{budget.transport}</strong></div>
        <div className="figure" title={`${TRANSPORT_HEADERS[budget.transport]} included`}>
          <span>On the wire, drone → base</span><strong data-testid="wire-rate">{formatRate(budget.drone_to_base)}</strong>
        </div>
        <div className="figure"><span>base → drone</span><strong>{formatRate(budget.base_to_drone)}</strong></div>
        {budget.share !== null && budget.rate_bps !== null && (
          <div className="figure"><span>Share of {formatRate(budget.rate_bps)}</span>
            <strong data-testid="budget-share">{(budget.share * 100).toFixed(1)} %</strong></div>
        )}
        <div className="figure muted"><span>Packets / s</span><strong>{budget.packets_per_s.toFixed(2)}</strong></div>
        {budget.control && (
          <div className="figure muted" data-testid="control-rate"
            title={`STATUS every ${budget.control.status_period_s} s and a PONG per keepalive, included above; at most ${budget.control.bound_bytes_per_s.toFixed(1)} B/s`}>
            <span>of which control</span><strong>about {budget.control.bytes_per_s.toFixed(1)} B/s</strong>
          </div>
        )}
      </div>
      {budget.error && (
        <div className="infeasible" role="alert" data-testid="budget-error">
          <strong>Over the link budget</strong> {budget.error}
          <div>{budget.over_budget.map((n) => (
            <button key={n} className="link chip" onClick={() => onSelect(n)}>{n}</button>
          ))}</div>
        </div>
      )}
      {delays.length > 0 && (
        <p className="muted" aria-label="Delay per subscription" title={LINK_DELAY_HELP}>
          Delay on the link (waiting for the packet and its air time, after the schedule): {delays.map(([n, d]) => `${n} ${d.toFixed(2)} s`).join(", ")}
        </p>
      )}
    </section>
  );
}
