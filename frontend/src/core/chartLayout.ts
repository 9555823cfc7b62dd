/**
 * Charts as lists of channels (several subscriptions on one chart): pure
 * edits that never leave an empty chart or a channel on two charts.
 *
 * @example chartsMove([["a"], ["b"]], "b", 0) // [["a", "b"]]
 */
export type Charts = string[][];

const tidy = (charts: Charts): Charts => charts.filter((c) => c.length > 0);

/** `c` on a chart of its own, at the end (nothing when already charted). */
export function chartsAdd(charts: Charts, c: string): Charts {
  return charts.some((x) => x.includes(c)) ? charts : [...charts, [c]];
}

export function chartsRemove(charts: Charts, c: string): Charts {
  return tidy(charts.map((x) => x.filter((y) => y !== c)));
}

/** Moves `c` onto chart `index` (as counted before the move). */
export function chartsMove(charts: Charts, c: string, index: number): Charts {
  const target = charts[index];
  if (!target || target.includes(c)) return charts;
  return tidy(charts.map((x, i) => (i === index ? [...x, c] : x.filter((y) => y !== c))));
}

/** Takes `c` off its chart onto a chart of its own. */
export function chartsSplit(charts: Charts, c: string): Charts {
  return [...chartsRemove(charts, c), [c]];
}
