import { describe, expect, it } from "vitest";
import { mergeModels, sameValue } from "./merge";
import { scenario1 } from "./testing/scenario1";
import type { ModdModel } from "./model.gen";

const edit = (m: ModdModel, f: (x: ModdModel) => void): ModdModel => { const c = structuredClone(m); f(c); return c; };

describe("three-way merge", () => {
  const base = scenario1();

  it("keeps both sides' edits of different elements and fields", () => {
    const mine = edit(base, (m) => { m.subscribers[0].periodS = "4.0"; });
    const theirs = edit(base, (m) => { m.subscribers[1].aggregation = "MAX"; m.publishers[0].periodS = "0.1"; });
    const r = mergeModels(base, mine, theirs);
    expect(r.conflicts).toEqual([]);
    expect(r.model.subscribers[0].periodS).toBe("4.0");
    expect(r.model.subscribers[1].aggregation).toBe("MAX");
    expect(r.model.publishers[0].periodS).toBe("0.1");
    expect(r.kept).toEqual([`/subscribers/${base.subscribers[0].name}`]);
  });

  it("reports a field both changed differently, and takes the chosen side", () => {
    const name = base.subscribers[0].name;
    const mine = edit(base, (m) => { m.subscribers[0].periodS = "4.0"; });
    const theirs = edit(base, (m) => { m.subscribers[0].periodS = "8.0"; });
    const r = mergeModels(base, mine, theirs);
    expect(r.conflicts).toEqual([{ pointer: `/subscribers/${name}/periodS`, base: base.subscribers[0].periodS, mine: "4.0", theirs: "8.0" }]);
    expect(r.model.subscribers[0].periodS).toBe("8.0");
    expect(mergeModels(base, mine, theirs, { [`/subscribers/${name}/periodS`]: "mine" }).model.subscribers[0].periodS).toBe("4.0");
  });

  it("adds what each side added and asks about a removal of an element the other changed", () => {
    const mine = edit(base, (m) => { m.subscribers.push({ name: "mine_1", topic: m.subscribers[0].topic, periodS: "1.0", aggregation: "MIN" }); });
    const theirs = edit(base, (m) => { m.subscribers.push({ name: "theirs_1", topic: m.subscribers[0].topic, periodS: "1.0", aggregation: "MAX" }); });
    const r = mergeModels(base, mine, theirs);
    expect(r.conflicts).toEqual([]);
    expect(r.model.subscribers.map((s) => s.name).slice(-2)).toEqual(["theirs_1", "mine_1"]);

    const gone = edit(base, (m) => { m.subscribers.splice(0, 1); });
    const changed = edit(base, (m) => { m.subscribers[0].periodS = "9.0"; });
    const r2 = mergeModels(base, changed, gone);
    expect(r2.conflicts.map((c) => c.pointer)).toEqual([`/subscribers/${base.subscribers[0].name}`]);
    expect(r2.model.subscribers.length).toBe(base.subscribers.length - 1);
    expect(mergeModels(base, changed, gone, { [`/subscribers/${base.subscribers[0].name}`]: "mine" }).model.subscribers.length).toBe(base.subscribers.length);
  });

  it("shows a conflict, dropping nothing, when two elements share a name on one side", () => {
    // a work in progress: a copied subscriber not renamed yet, then edited
    const first = base.subscribers[0];
    const mine = edit(base, (m) => { m.subscribers.push({ ...structuredClone(first), periodS: "7.5" }); });
    const theirs = edit(base, (m) => { m.subscribers[1].aggregation = "MAX"; });
    const r = mergeModels(base, mine, theirs);
    expect(r.conflicts.map((c) => c.pointer)).toEqual(["/subscribers"]);
    const kept = mergeModels(base, mine, theirs, { "/subscribers": "mine" }).model.subscribers;
    expect(kept.filter((s) => s.name === first.name).map((s) => s.periodS)).toEqual([first.periodS, "7.5"]);
  });

  it("compares values semantically (key order)", () => {
    expect(sameValue({ a: 1, b: [1, { c: 2, d: 3 }] }, { b: [1, { d: 3, c: 2 }], a: 1 })).toBe(true);
    expect(sameValue({ a: 1 }, { a: 1, b: 2 })).toBe(false);
  });
});
