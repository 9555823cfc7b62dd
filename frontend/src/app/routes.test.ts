import { describe, expect, it } from "vitest";
import { formatRoute, parseRoute } from "./routes";

describe("routes", () => {
  it("round-trips project, view and panel", () => {
    for (const path of ["/", "/projects/3", "/projects/3/scientist/monitor", "/projects/12/operator/history"]) {
      expect(formatRoute(parseRoute(path))).toBe(path);
    }
  });
  it("ignores what it does not know", () => {
    expect(parseRoute("/projects/x")).toEqual({ project: null, view: null, panel: null });
    expect(parseRoute("/projects/3/pilot/plan")).toEqual({ project: 3, view: null, panel: "plan" });
  });
});
