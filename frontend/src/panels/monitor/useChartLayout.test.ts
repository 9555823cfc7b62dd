import { describe, expect, it } from "vitest";
import { keepSubscribed } from "./useChartLayout";
import type { DataSource } from "../../dataSources/types";

describe("keepSubscribed", () => {
  it("holds exactly the charted channels", () => {
    const live = new Set<string>();
    const source = { subscribe: (c: string) => { live.add(c); return () => live.delete(c); } } as unknown as DataSource;
    keepSubscribed(source, ["a", "b"]);
    expect([...live].sort()).toEqual(["a", "b"]);
    keepSubscribed(source, ["b", "c"]);
    expect([...live].sort()).toEqual(["b", "c"]);
    keepSubscribed(source, []);
    expect(live.size).toBe(0);
  });
});
