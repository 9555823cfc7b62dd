/**
 * The one form in which the workbench names a topic: its full name
 * (`drone.sensor.variable`) and, when the variable has one, its unit — the
 * same in the diagram, the plan, the Monitor, the inspector, the archives
 * and the deploy diff.
 *
 * @example
 *   topicLabel(model, "usv.accelerometer.accel_x")      // "usv.accelerometer.accel_x (m/s²)"
 *   topicLabel(model, "usv.gps.latitude")               // "usv.gps.latitude" (unit NONE)
 *   variableLabel(ref)                                  // "accel_x (m/s²)" (under its sensor's heading)
 *   topicLabel(model, "usv.gone.x")                     // "usv.gone.x" (not in the model: the name alone)
 *   subscriptionLabel(model, sub)                       // "usv.accelerometer.accel_x (m/s²) AVERAGE every 2.0 s"
 */
import { AGGREGATION } from "./contracts.gen";
import type { ModdModel } from "./model.gen";
import { unitLabel } from "./chartData";
import { findTopicByName, type TopicRef } from "./query";

/** A topic the model lists (query.listTopics), as every panel shows it. */
export function topicRefLabel(t: TopicRef): string {
  const unit = unitLabel(t.variable.unit);
  return unit ? `${t.name} (${unit})` : t.name;
}

/**
 * A topic under its sensor's heading (the Quick subscription's list, grouped by
 * sensor, in the narrow palette): the variable and its unit; the full name is
 * the option's tooltip and is spelled out under the form.
 */
export function variableLabel(t: TopicRef): string {
  const unit = unitLabel(t.variable.unit);
  return unit ? `${t.variable.name} (${unit})` : t.variable.name;
}

/**
 * A topic by its full name, as every panel shows it: the first of the models
 * that has it gives the unit (a deploy diff passes the new and the deployed
 * model, so that a removed topic keeps its unit); outside them, the name alone.
 */
export function topicLabel(model: ModdModel | ReadonlyArray<ModdModel | undefined> | undefined, topic: string): string {
  for (const m of Array.isArray(model) ? model : [model as ModdModel | undefined]) {
    const t = m && findTopicByName(m, topic);
    if (t) return topicRefLabel(t);
  }
  return topic;
}

/** A subscription as every panel tells it: its topic (as topicLabel), aggregation and period. */
export function subscriptionLabel(
  model: ModdModel | ReadonlyArray<ModdModel | undefined> | undefined,
  s: { topic: string; aggregation: string; periodS: string | number; percentile?: number } & EventParameters,
): string {
  return `${s.topic ? topicLabel(model, s.topic) : "(no topic)"} ${aggregationLabel(s)} every ${String(s.periodS)} s`;
}

/** The parameters of an event subscription (ON_CHANGE, THRESHOLD) a label spells. */
export interface EventParameters {
  deadband?: number;
  deadbandPercent?: number;
  level?: number;
  hysteresis?: number;
  crossing?: string;
  maxEvents?: number;
}

/** A subscription's aggregation as the plan and the delivered values name it:
 * PERCENTILE with its p, `PERCENTILE(95)`; an event subscription with its
 * parameters then N, `ON_CHANGE(0.5, 4)`, `THRESHOLD(DOWN 5, 0.2)`
 * (modd_contracts/labels.py and events.py). */
export function aggregationLabel(s: { aggregation: string; percentile?: number } & EventParameters): string {
  if (s.aggregation === AGGREGATION.PERCENTILE && s.percentile !== undefined) return `${s.aggregation}(${String(s.percentile)})`;
  const n = s.maxEvents !== undefined ? `, ${String(s.maxEvents)}` : "";
  if (s.aggregation === AGGREGATION.ON_CHANGE) {
    const d = s.deadbandPercent !== undefined ? `${String(s.deadbandPercent)}%` : String(s.deadband ?? 0);
    return `${s.aggregation}(${d}${n})`;
  }
  if (s.aggregation === AGGREGATION.THRESHOLD && s.level !== undefined) {
    const h = n || s.hysteresis ? `, ${String(s.hysteresis ?? 0)}` : "";
    return `${s.aggregation}(${(s.crossing ?? "both").toUpperCase()} ${String(s.level)}${h}${n})`;
  }
  return s.aggregation;
}
