/**
 * What changed in the plan between two planner documents: the figures a
 * person reads (hyperperiod, messages, bytes/s on the link, delays, buffer
 * sizes), each as before → after. Both documents come from the same
 * planning engine; nothing is re-planned here.
 *
 * @example
 *   planChanges(before, after)
 *   // [{ key: "hyperperiod", label: "hyperperiod", before: "2.0 s", after: "10.0 s" },
 *   //  { key: "delay:sub_3", label: "sub_3 delay", before: "0.0 s", after: "2.0 s" }]
 */
import { formatRate, type PlanJson } from "./plan";

export interface PlanChange {
  /** Stable key, e.g. "hyperperiod", "delay:sub_3", "buffer:usv.gps.lat". */
  key: string;
  label: string;
  before: string;
  after: string;
}

const secs = (s: string | number | null | undefined) => (s === null || s === undefined ? "—" : `${s} s`);

/** How a figure names a topic (core/topicLabel.ts gives the workbench's one form); the bare name by default. */
export type TopicNamer = (topic: string) => string;

/** The headline figures of a plan, formatted, by key. */
export function planFigures(plan: PlanJson, name: TopicNamer = (t) => t): Map<string, [string, string]> {
  const out = new Map<string, [string, string]>();
  out.set("hyperperiod", ["hyperperiod", secs(plan.hyperperiod_s)]);
  out.set("messages", ["messages per hyperperiod", String(plan.messages_per_hyperperiod)]);
  out.set("bytes", ["link, drone → base", formatRate(plan.predicted_link_bytes_per_s.drone_to_base)]);
  out.set("maxDelay", ["max delay", secs(plan.max_delay_s)]);
  for (const [name, d] of Object.entries(plan.delays)) out.set(`delay:${name}`, [`${name} delay`, secs(d)]);
  for (const [topic, n] of Object.entries(plan.buffer_sizes)) out.set(`buffer:${topic}`, [`${name(topic)} buffer`, String(n)]);
  return out;
}

/** Figures that differ between two plans (added or removed ones show "—" on the missing side). */
export function planChanges(before: PlanJson | null, after: PlanJson, name?: TopicNamer): PlanChange[] {
  if (!before) return [];
  const a = planFigures(before, name);
  const b = planFigures(after, name);
  const out: PlanChange[] = [];
  for (const key of new Set([...a.keys(), ...b.keys()])) {
    const x = a.get(key);
    const y = b.get(key);
    if (x?.[1] === y?.[1]) continue;
    out.push({ key, label: (y ?? x)![0], before: x?.[1] ?? "—", after: y?.[1] ?? "—" });
  }
  return out;
}
