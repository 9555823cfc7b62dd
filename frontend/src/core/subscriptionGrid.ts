/**
 * Several subscriptions in one choice: every topic × period × aggregation the
 * scientist picked (Quick subscription). Pure; the form dispatches one
 * `addSubscriber` per entry.
 *
 * @example
 *   subscriptionGrid(["usv.a.x"], parsePeriods("2.0, 0.25").periods, ["AVERAGE"])
 *   // [{ topic: "usv.a.x", periodS: "2.0", aggregation: "AVERAGE" }, { ..., periodS: "0.25", ... }]
 */
import { canonicalDecimal } from "./canonical";
import type { Aggregation } from "./model.gen";

export interface SubscriptionChoice {
  topic: string;
  periodS: string;
  aggregation: Aggregation;
}

/** Periods written "2.0, 0.25" or "2 0.25": the canonical decimals, and what is not a period. */
export function parsePeriods(text: string): { periods: string[]; bad: string[] } {
  const periods: string[] = [];
  const bad: string[] = [];
  for (const word of text.split(/[\s,;]+/).filter(Boolean)) {
    const p = canonicalDecimal(word);
    if (p === null || Number(p) <= 0) bad.push(word);
    else if (!periods.includes(p)) periods.push(p);
  }
  return { periods, bad };
}

export function subscriptionGrid(topics: string[], periods: string[], aggregations: Aggregation[]): SubscriptionChoice[] {
  return topics.flatMap((topic) => periods.flatMap((periodS) => aggregations.map((aggregation) => ({ topic, periodS, aggregation }))));
}
