import { describe, expect, it } from "vitest";
import { alignSeries, axisLabel, panRange, unitLabel, visibleRange, zoomRange } from "./chartData";
import { chartsAdd, chartsMove, chartsRemove, chartsSplit } from "./chartLayout";

describe("chart data", () => {
  it("aligns series with their own timestamps", () => {
    expect(alignSeries([[{ t: 1, value: 5 }, { t: 3, value: 6 }], [{ t: 2, value: 7 }]])).toEqual([[1, 2, 3], [5, null, 6], [null, 7, null]]);
  });

  it("gives one point a span of seconds, not years", () => {
    const [from, to] = visibleRange({ follow: true, spanS: 60 }, 1_800_000_000);
    expect(to - from).toBe(60);
    expect(visibleRange({ follow: false, from: 1, to: 2 }, 99)).toEqual([1, 2]);
  });

  it("zooms and pans a range", () => {
    expect(zoomRange([0, 100], 0.5)).toEqual({ follow: false, from: 25, to: 75 });
    expect(panRange([0, 100], -0.5)).toEqual({ follow: false, from: -50, to: 50 });
  });

  it("labels units", () => {
    expect(unitLabel("METER_PER_SECOND_SQUARED")).toBe("m/s²");
    expect(unitLabel("DEGREE_CELSIUS", "COUNT")).toBe("samples");
    // the exact window statistics are in the topic's unit (a deviation, a range, a median)
    for (const a of ["MEDIAN", "STDDEV", "RANGE"]) expect(unitLabel("DEGREE_CELSIUS", a)).toBe("°C");
    expect(axisLabel(["m/s²", "m/s²", "°C"])).toBe("m/s² · °C");
  });
});

describe("chart layout", () => {
  it("puts several subscriptions on one chart and takes them off again", () => {
    let c = chartsAdd(chartsAdd([], "a"), "b");
    expect(c).toEqual([["a"], ["b"]]);
    c = chartsMove(c, "b", 0);
    expect(c).toEqual([["a", "b"]]);
    expect(chartsSplit(c, "a")).toEqual([["b"], ["a"]]);
    expect(chartsRemove(c, "a")).toEqual([["b"]]);
    expect(chartsAdd(c, "a")).toBe(c);
  });
});
