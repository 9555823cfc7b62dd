/**
 * The scientist's shortcut: topics, periods and aggregations, then Subscribe —
 * a subscriber connected to its topic for every topic × period × aggregation
 * chosen (a plain click adds a topic or an aggregation to the choice or takes it
 * out, every aggregation listed; periods are written "2.0, 0.25"). After a submit
 * the last subscription made is selected: Duplicate (Ctrl+D) makes it twice. The topics are grouped under their sensor's name, each
 * by its variable and unit so that the narrow palette cuts no name (the full
 * name is the tooltip); what will be made is spelled out in full under the form.
 */
import { useState } from "react";
import { AggregationValues, type Aggregation } from "../core/model.gen";
import { AGGREGATION } from "../core/contracts.gen";
import { listTopics } from "../core/query";
import { nextPosition } from "../core/graph";
import { currentModel } from "../core/workbench";
import { topicLabel, topicRefLabel, variableLabel } from "../core/topicLabel";
import { parsePeriods, subscriptionGrid } from "../core/subscriptionGrid";
import { useEditorStore, useModel } from "./useEditor";

/** PERCENTILE needs its p: it is written PERCENTILE(95) in the text view, or given
 * its percentile in the inspector, not chosen here. */
const QUICK_AGGREGATIONS = AggregationValues.filter((a) => a !== AGGREGATION.PERCENTILE && a !== AGGREGATION.ON_CHANGE && a !== AGGREGATION.THRESHOLD);

const selected = (e: React.ChangeEvent<HTMLSelectElement>) => [...e.target.selectedOptions].map((o) => o.value);

/**
 * A plain click on an option adds it to the choice or takes it out (no Ctrl or Shift:
 * a choice of several is the usual case here), keeping at least one.
 */
function toggleOnClick<T extends string>(chosen: readonly T[], set: (v: T[]) => void) {
  return (e: React.MouseEvent<HTMLSelectElement>) => {
    const option = e.target as HTMLElement;
    if (option.tagName !== "OPTION" || e.ctrlKey || e.metaKey || e.shiftKey) return;
    e.preventDefault();
    const value = (option as HTMLOptionElement).value as T;
    const next = chosen.includes(value) ? chosen.filter((x) => x !== value) : [...chosen, value];
    if (next.length) set(next);
  };
}

export function QuickSubscribe() {
  const store = useEditorStore();
  const model = useModel();
  const topics = listTopics(model);
  const [picked, setTopics] = useState<string[]>([]);
  const [periodText, setPeriod] = useState("1.0");
  const [aggregations, setAggregations] = useState<Aggregation[]>([AGGREGATION.AVERAGE]);
  const known = picked.filter((t) => topics.some((x) => x.name === t));
  const chosen = known.length ? known : topics.slice(0, 1).map((t) => t.name);
  const { periods, bad } = parsePeriods(periodText);
  const grid = subscriptionGrid(chosen, periods, aggregations);
  return (
    <form
      className="quick-subscribe"
      aria-label="Quick subscription"
      onSubmit={(e) => {
        e.preventDefault();
        for (const g of grid) {
          store.dispatch({ type: "addSubscriber", ...g, pos: nextPosition(currentModel(store.getState().wb), "subscriber") });
        }
      }}
    >
      <label>Topic
        <select multiple size={Math.min(6, topics.length + model.drone.sensors.length) || 1} value={chosen}
          title={chosen.join(", ")} onChange={(e) => setTopics(selected(e))} onMouseDown={toggleOnClick(chosen, setTopics)} disabled={!topics.length}>
          {model.drone.sensors.map((sensor) => (
            <optgroup key={sensor.name} label={sensor.name} title={sensor.description || undefined}>
              {topics.filter((t) => t.sensor === sensor).map((t) => (
                <option key={t.id} value={t.name} title={topicRefLabel(t)}>{variableLabel(t)}</option>
              ))}
            </optgroup>
          ))}
        </select>
      </label>
      <label>Every (s)
        <input value={periodText} onChange={(e) => setPeriod(e.target.value)} inputMode="decimal" size={5}
          aria-invalid={bad.length > 0} title="One period or several: 2.0, 0.25" />
      </label>
      {bad.length > 0 && <span className="error" role="alert">Not a period: {bad.join(", ")}</span>}
      <label>Aggregation
        <select multiple size={QUICK_AGGREGATIONS.length} value={aggregations} onChange={(e) => setAggregations(selected(e) as Aggregation[])}
          onMouseDown={toggleOnClick(aggregations, setAggregations)} title="Every aggregation is listed; a click adds one or takes it out">
          {QUICK_AGGREGATIONS.map((a) => <option key={a}>{a}</option>)}
        </select>
      </label>
      <output className="quick-subscribe-summary" aria-label="Subscriptions to make">
        {grid.length === 1 ? "" : `${grid.length} subscriptions: `}
        {grid.map((g) => `${topicLabel(model, g.topic)} ${g.aggregation} every ${g.periodS} s`).join("; ")}
      </output>
      <button type="submit" disabled={!grid.length || bad.length > 0}>{grid.length > 1 ? `Subscribe (${grid.length})` : "Subscribe"}</button>
    </form>
  );
}
