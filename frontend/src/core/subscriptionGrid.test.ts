import { describe, expect, it } from "vitest";
import { parsePeriods, subscriptionGrid } from "./subscriptionGrid";

describe("subscriptionGrid", () => {
  it("makes every topic × period × aggregation once", () => {
    const { periods, bad } = parsePeriods("2, 0.25;2.0  .5");
    expect(periods).toEqual(["2.0", "0.25", "0.5"]);
    expect(bad).toEqual([]);
    const grid = subscriptionGrid(["usv.a.x", "usv.a.y"], periods, ["AVERAGE", "MAX"]);
    expect(grid).toHaveLength(2 * 3 * 2);
    expect(new Set(grid.map((g) => `${g.topic} ${g.periodS} ${g.aggregation}`)).size).toBe(12);
    expect(grid[0]).toEqual({ topic: "usv.a.x", periodS: "2.0", aggregation: "AVERAGE" });
  });

  it("names what is not a period", () => {
    expect(parsePeriods("1.0, abc, -2, 0").bad).toEqual(["abc", "-2", "0"]);
  });
});
