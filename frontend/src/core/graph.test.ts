import { describe, expect, it } from "vitest";
import { modelToGraph, defaultPosition } from "./graph";
import { scenario1 } from "./testing/scenario1";
import { emptyModel } from "./templates";

describe("modelToGraph", () => {
  it("has one node per element of scenario 1", () => {
    const g = modelToGraph(scenario1());
    const kinds = g.nodes.map((n) => n.kind);
    expect(kinds.filter((k) => k === "topic")).toHaveLength(3);
    expect(kinds.filter((k) => k === "subscriber")).toHaveLength(7);
    expect(kinds.filter((k) => k === "publisher")).toHaveLength(1);
    expect(kinds.filter((k) => k === "sensor")).toHaveLength(1);
    expect(g.nodes).toHaveLength(1 + 2 + 1 + 3 + 1 + 7);
    expect(new Set(g.nodes.map((n) => n.id)).size).toBe(g.nodes.length);
  });

  it("draws publisher → topic and topic → subscriber edges", () => {
    const g = modelToGraph(scenario1());
    const pubs = g.edges.filter((e) => e.kind === "publishes");
    expect(pubs.map((e) => e.target)).toEqual(["topic:accelerometer.accel_x", "topic:accelerometer.accel_y", "topic:accelerometer.accel_z"]);
    const subs = g.edges.filter((e) => e.kind === "subscribes");
    expect(subs).toHaveLength(7);
    expect(subs.find((e) => e.target === "sub:sub_5")?.source).toBe("topic:accelerometer.accel_z");
    expect(g.edges.find((e) => e.kind === "link")).toMatchObject({ source: "pubBroker", target: "subBroker" });
  });

  it("skips edges to unknown topics (shown as diagnostics instead)", () => {
    const m = scenario1();
    m.subscribers[0].topic = "usv.nothing.here";
    m.subscribers[1].topic = "";
    const g = modelToGraph(m);
    expect(g.edges.filter((e) => e.kind === "subscribes")).toHaveLength(5);
  });

  it("uses saved positions and a column layout otherwise", () => {
    const m = scenario1();
    m.layout = { nodes: { "sub:sub_2": { x: 5, y: 6 } } };
    const g = modelToGraph(m);
    expect(g.nodes.find((n) => n.id === "sub:sub_2")?.position).toEqual({ x: 5, y: 6 });
    expect(g.nodes.find((n) => n.id === "sub:sub_1")?.position).toEqual(defaultPosition("subscriber", 0));
    expect(g.nodes.find((n) => n.id === "sub:sub_3")?.position).toEqual(defaultPosition("subscriber", 2));
  });

  it("maps an empty project to the drone, the brokers and the link", () => {
    const g = modelToGraph(emptyModel());
    expect(g.nodes.map((n) => n.id)).toEqual(["drone", "pubBroker", "subBroker"]);
    expect(g.edges.map((e) => e.id)).toEqual(["link"]);
  });
});

describe("nextPosition", () => {
  it("puts a new element below the lowest of its kind", async () => {
    const { nextPosition, ROW_HEIGHT } = await import("./graph");
    const m = scenario1();
    m.layout = { nodes: { "sub:sub_4": { x: 900, y: 1000 } } };
    expect(nextPosition(m, "subscriber")).toEqual({ x: 900, y: 1000 + ROW_HEIGHT });
    expect(nextPosition(emptyModel(), "sensor")).toEqual(defaultPosition("sensor", 0));
  });
});
