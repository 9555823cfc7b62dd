/**
 * The planner's JSON (metamodel/src/modd_plan/planjson.py, docs/planning.md)
 * as the UI reads it, and the pure computations the plan panel draws from.
 * Every number shown comes from this document: nothing is re-planned here.
 */
import type { ModdModel } from "./model.gen";
import { findTopicByName } from "./query";
import { subscriberId } from "./ids";

import type {
  PlanDocument,
  PlanInfeasible,
  PlanLinkBudget,
  PlanSlot,
  PlanStream,
  PlanTopic,
  PredictedLink,
} from "./contracts.gen";

// The plan JSON's types are generated from its contract
// (metamodel/src/modd_contracts/schemas/plan.schema.json, core/contracts.gen.ts).
export type { PlanSlot, PlanStream, PlanTopic };
export type PlanJson = PlanDocument;
export type LinkCost = PredictedLink;
/** The declared transport's link budget (metamodel/src/modd_plan/linkbudget.py). */
export type LinkBudget = PlanLinkBudget;
export type Infeasibility = PlanInfeasible;

/** What a transport's bytes/s include, in words. */
export const TRANSPORT_HEADERS: Record<LinkBudget["transport"], string> = {
  tcp: "IP + TCP headers and ACKs",
  udp: "IP + UDP headers",
  serial: "COBS + CRC framing",
};

export interface TopicRow {
  topic: string;
  bufferSize: number | null;
  publicationPeriodS: string | null;
  subscribers: Array<{ name: string; stream: string; delayS: string | null }>;
}

/** One row per planned topic: its buffer size and each subscriber with its delay. */
export function topicRows(plan: PlanJson): TopicRow[] {
  return plan.topics.map((t) => ({
    topic: t.name,
    bufferSize: plan.buffer_sizes[t.name] ?? t.buffer_size,
    publicationPeriodS: t.publication_period_s,
    subscribers: Object.entries(plan.subscriptions)
      .filter(([, key]) => key.startsWith(`${t.name}/`))
      .map(([name, key]) => ({ name, stream: key, delayS: plan.delays[name] ?? null }))
      .sort((a, b) => a.name.localeCompare(b.name, undefined, { numeric: true })),
  }));
}

export interface TimelineMark {
  slot: number;
  /** Date within the hyperperiod, in seconds. */
  t: number;
  /** Position within the visible window, 0..1. */
  x: number;
  streams: string[];
}

/**
 * Slots of the schedule that fall in the visible window [from, to] (seconds),
 * with their position in it, for the zoomable timeline.
 */
export function timeline(plan: PlanJson, from = 0, to = Number(plan.hyperperiod_s)): TimelineMark[] {
  const keys = new Map(plan.schedule.streams.map((s) => [s.id, s.key]));
  const span = Math.max(to - from, 1e-9);
  return plan.schedule.slots
    .map((s) => ({ slot: s.slot, t: Number(s.date_s), streams: s.streams.map((id) => keys.get(id) ?? `#${id}`) }))
    .filter((m) => m.t >= from - 1e-9 && m.t <= to + 1e-9)
    .map((m) => ({ ...m, x: (m.t - from) / span }));
}

/** Clamps a zoom window inside [0, hyperperiod] keeping at least one microsecond. */
export function zoomWindow(hyperperiod: number, center: number, width: number): [number, number] {
  const w = Math.min(Math.max(width, 1e-6), hyperperiod);
  let from = center - w / 2;
  from = Math.min(Math.max(from, 0), hyperperiod - w);
  return [from, from + w];
}

/** Element ids an infeasibility concerns (its topic and subscribers), with the reason. */
export function infeasibleElements(model: ModdModel, plan: PlanJson): Map<string, string[]> {
  const out = new Map<string, string[]>();
  const note = (id: string, reason: string) => out.set(id, [...(out.get(id) ?? []), reason]);
  for (const x of plan.infeasible) {
    const topic = findTopicByName(model, x.topic);
    if (topic) note(topic.id, x.reason);
    for (const s of x.subscribers) note(subscriberId(s), x.reason);
  }
  return out;
}

/** Bytes per second in a human unit. */
export function formatRate(bytesPerS: number): string {
  if (typeof bytesPerS !== "number" || !Number.isFinite(bytesPerS)) return "—";
  if (bytesPerS >= 1e6) return `${(bytesPerS / 1e6).toFixed(2)} MB/s`;
  if (bytesPerS >= 1e3) return `${(bytesPerS / 1e3).toFixed(2)} kB/s`;
  return `${bytesPerS.toFixed(0)} B/s`;
}
