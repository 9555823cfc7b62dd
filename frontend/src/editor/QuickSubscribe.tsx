/**
 * The scientist's shortcut: topic, period and aggregation, then Add — one
 * subscriber connected to its topic in a few clicks. The topics are grouped
 * by sensor, each under its full name (as everywhere in the workbench) with
 * its unit.
 */
import { useState } from "react";
import { AggregationValues, type Aggregation } from "../core/model.gen";
import { AGGREGATION } from "../core/contracts.gen";
import { listTopics } from "../core/query";
import { nextPosition } from "../core/graph";
import { currentModel } from "../core/workbench";
import { topicLabel } from "../core/topicLabel";
import { useEditorStore, useModel } from "./useEditor";

export function QuickSubscribe() {
  const store = useEditorStore();
  const model = useModel();
  const topics = listTopics(model);
  const [topic, setTopic] = useState("");
  const [periodS, setPeriod] = useState("1.0");
  const [aggregation, setAggregation] = useState<Aggregation>(AGGREGATION.AVERAGE);
  const chosen = topic || topics[0]?.name || "";
  return (
    <form
      className="quick-subscribe"
      aria-label="Quick subscription"
      onSubmit={(e) => {
        e.preventDefault();
        if (!chosen) return;
        store.dispatch({ type: "addSubscriber", topic: chosen, periodS, aggregation, pos: nextPosition(currentModel(store.getState().wb), "subscriber") });
      }}
    >
      <label>Topic
        <select value={chosen} title={chosen} onChange={(e) => setTopic(e.target.value)} disabled={!topics.length}>
          {model.drone.sensors.map((sensor) => (
            <optgroup key={sensor.name} label={`${sensor.name}${sensor.description ? ` — ${sensor.description}` : ""}`}>
              {topics.filter((t) => t.sensor === sensor).map((t) => <option key={t.id} value={t.name}>{topicLabel(model, t.name)}</option>)}
            </optgroup>
          ))}
        </select>
      </label>
      <label>Every (s)
        <input value={periodS} onChange={(e) => setPeriod(e.target.value)} inputMode="decimal" size={5} />
      </label>
      <label>Aggregation
        <select value={aggregation} onChange={(e) => setAggregation(e.target.value as Aggregation)}>
          {AggregationValues.map((a) => <option key={a}>{a}</option>)}
        </select>
      </label>
      <button type="submit" disabled={!chosen}>Subscribe</button>
    </form>
  );
}
