/**
 * The Monitor's "Active alerts" (core/alerts.ts says what active means): every
 * alert subscription's for the operator, the view's own for the others; each
 * with its true time (the crossing sample's), acknowledge and clear; and the
 * sound toggle.
 */
import { activeAlerts, describeAlert } from "../../core/alerts";
import type { ViewRole } from "../../core/roles";
import { alertTime } from "../../app/AlertBanner";
import { SoundToggle } from "../../app/SoundToggle";
import { useAlerts } from "../../app/useAlerts";

export function ActiveAlerts({ role }: { role: ViewRole }) {
  const { alerts, rules, acknowledge, clear } = useAlerts();
  if (rules.length === 0) return null;
  const active = activeAlerts(alerts, rules, role);
  return (
    <section className="active-alerts" aria-label="Active alerts">
      <h3>Active alerts ({active.length})</h3>
      {active.length === 0 && <p className="muted">None: {rules.map((r) => r.subscriber).join(", ")} watched.</p>}
      <ul>
        {active.map((a) => (
          <li key={a.id} data-testid={`active-alert-${a.subscriber}`}>
            <span>{describeAlert(a, rules.find((r) => r.subscriber === a.subscriber), alertTime)}</span>
            {a.acknowledged ? <span className="muted">acknowledged</span>
              : <button onClick={() => acknowledge(a.id)}>Acknowledge</button>}
            <button onClick={() => clear(a.id)}>Clear</button>
          </li>
        ))}
      </ul>
      <SoundToggle />
    </section>
  );
}
