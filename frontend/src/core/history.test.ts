import { describe, expect, it } from "vitest";
import { canRedo, canUndo, createHistory, push, redo, reset, undo } from "./history";

describe("history", () => {
  it("undoes and redoes in order", () => {
    let h = createHistory("a");
    h = push(h, "b");
    h = push(h, "c");
    h = undo(h);
    expect(h.present).toBe("b");
    h = undo(h);
    expect(h.present).toBe("a");
    expect(canUndo(h)).toBe(false);
    h = redo(h);
    h = redo(h);
    expect(h.present).toBe("c");
    expect(canRedo(h)).toBe(false);
  });

  it("clears the redo stack on a new push", () => {
    let h = push(push(createHistory(1), 2), 3);
    h = undo(h);
    h = push(h, 4);
    expect(canRedo(h)).toBe(false);
    expect(undo(h).present).toBe(2);
  });

  it("coalesces pushes with the same key into one step", () => {
    let h = createHistory("");
    for (const v of ["s", "su", "sub"]) h = push(h, v, "field:name");
    expect(h.past).toEqual([""]);
    h = push(h, "x", "field:other");
    expect(h.past).toEqual(["", "sub"]);
    // After an undo the same key starts a new step.
    h = undo(h);
    h = push(h, "sub2", "field:name");
    expect(h.past).toEqual(["", "sub"]);
  });

  it("bounds the past and ignores no-op pushes", () => {
    let h = createHistory(0, 3);
    for (let i = 1; i <= 10; i += 1) h = push(h, i);
    expect(h.past).toEqual([7, 8, 9]);
    expect(push(h, h.present)).toBe(h);
    expect(undo(createHistory(0))).toEqual(createHistory(0));
    expect(reset(h, 42)).toMatchObject({ past: [], present: 42, future: [] });
  });
});
