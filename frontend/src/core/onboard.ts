/**
 * What the drone's on-board processes did with a deploy (`onboard` in the
 * SubBroker's deploy reply and status, docs/sensors.md "Deploying to a running
 * drone"), in words: one line per process, each instrument's action and, when
 * it cannot read, why (a missing device, a busy one, an invalid model).
 * Bounded and tolerant: a field of the wrong type reads as absent.
 */
export interface OnboardLine {
  process: string;
  ok: boolean;
  text: string;
}

const MAX_ITEMS = 40;

function str(x: unknown): string {
  return typeof x === "string" ? x.slice(0, 200) : "";
}

function sensorWords(s: Record<string, unknown>): string {
  const problem = str(s.problem);
  const state = str(s.state);
  return `${str(s.sensor)} ${str(s.action)}${problem ? ` — ${problem}` : state && s.action !== "stopped" ? ` (${state})` : ""}`;
}

function topicWords(r: Record<string, unknown>): string[] {
  return (["added", "changed", "removed"] as const).flatMap((k) => {
    const list = Array.isArray(r[k]) ? (r[k] as unknown[]).map(str).filter(Boolean) : [];
    return list.length ? [`${k} ${list.slice(0, MAX_ITEMS).join(", ")}`] : [];
  });
}

function processWords(r: Record<string, unknown>, changedOnly: boolean): string {
  const items = Array.isArray(r.sensors)
    ? (r.sensors as unknown[])
      .filter((s): s is Record<string, unknown> => !!s && typeof s === "object")
      .filter((s) => !changedOnly || s.action !== "unchanged" || s.ok !== true)
      .slice(0, MAX_ITEMS).map(sensorWords)
    : topicWords(r);
  const problem = str(r.problem);
  return [problem, ...items].filter(Boolean).join("; ") || (r.ok === true ? "applied" : "not applied");
}

/** The `onboard` object as lines, processes in name order; [] when absent or not an object.
 * `changedOnly`: leave out the instruments a deploy left as they were and that read. */
export function onboardLines(onboard: unknown, changedOnly = false): OnboardLine[] {
  if (!onboard || typeof onboard !== "object" || Array.isArray(onboard)) return [];
  return Object.entries(onboard as Record<string, unknown>)
    .filter((e): e is [string, Record<string, unknown>] => !!e[1] && typeof e[1] === "object")
    .sort(([a], [b]) => a.localeCompare(b))
    .slice(0, 8)
    .map(([process, r]) => ({ process, ok: r.ok === true, text: processWords(r, changedOnly) }));
}
