/**
 * The alert banner across the top of the views its alert names (core/alerts,
 * `alert = scientist + operator` in the model): the newest active alert this
 * view has not acknowledged (active, or back to normal unseen), with its true time (the crossing sample's, on the
 * drone's clock) and when its window arrived. role="alert", so a screen reader
 * says it at once. The sound (off by default) plays for each alert raised
 * while it is on.
 */
import { useEffect, useState } from "react";
import { localTimeMs } from "../core/numberFormat";
import { describeAlert, shownTo, unacknowledged } from "../core/alerts";
import { useEditor } from "../editor/useEditor";
import { beep, soundOn, useAlerts, useWatchAlerts } from "./useAlerts";
import { SoundToggle } from "./SoundToggle";

/** Clock time to the millisecond: an alert's time says when the sample crossed. */
export const alertTime = (t: number) => localTimeMs(t);

export function AlertBanner() {
  const role = useEditor((s) => s.wb.role);
  const { alerts, rules, acknowledge, acknowledgeAll, onRaised } = useAlerts();
  useWatchAlerts(rules);
  const [, setSoundState] = useState(soundOn());
  useEffect(() => onRaised((a) => {
    const rule = rules.find((r) => r.subscriber === a.subscriber);
    if (rule && shownTo(rule, role) && soundOn()) beep();
  }), [onRaised, rules, role]);
  const [shown, ...older] = unacknowledged(alerts, rules, role);
  if (!shown) return null;
  const rule = rules.find((r) => r.subscriber === shown.subscriber);
  return (
    <div className="alert-banner" role="alert" aria-label="Alert" data-testid="alert-banner"
      data-alert={shown.id} data-event-ns={Math.round(shown.t * 1e9)} data-delivered-ns={shown.deliveredNs ?? ""}>
      <strong>Alert</strong>
      <span>{describeAlert(shown, rule, alertTime)}</span>
      <span className="muted-light">
        {shown.active ? "active" : `back ${shown.direction === "up" ? "below" : "above"} the level`} · window arrived {alertTime(shown.receivedMs / 1000)}
      </span>
      <button onClick={() => acknowledge(shown.id)}>Acknowledge</button>
      {older.length > 0 && <button onClick={() => acknowledgeAll(role)}>Acknowledge all ({older.length + 1})</button>}
      <SoundToggle onChange={setSoundState} />
    </div>
  );
}
