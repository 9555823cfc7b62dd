import { describe, expect, it } from "vitest";
import { offsetOf, rangeOf } from "./positions";

describe("offsetOf", () => {
  const text = "ab\ncde\n\nf";
  it("maps 1-based line:col to offsets", () => {
    expect(offsetOf(text, 1, 1)).toBe(0);
    expect(offsetOf(text, 2, 3)).toBe(5);
    expect(offsetOf(text, 4, 1)).toBe(8);
  });
  it("clamps past the end of a line or the text", () => {
    expect(offsetOf(text, 1, 99)).toBe(2);
    expect(offsetOf(text, 99, 1)).toBe(text.length);
  });
});

describe("rangeOf", () => {
  const text = "Subscriber s(1, AVERAGED);\nx";
  it("spans the located text when the diagnostic has an end", () => {
    const r = rangeOf(text, { line: 1, col: 17, end_line: 1, end_col: 25 });
    expect(text.slice(r.from, r.to)).toBe("AVERAGED");
  });
  it("spans lines", () => {
    const r = rangeOf(text, { line: 1, col: 26, end_line: 2, end_col: 2 });
    expect(text.slice(r.from, r.to)).toBe(";\nx");
  });
  it("marks one character without an end, and never an empty or reversed range", () => {
    expect(rangeOf(text, { line: 1, col: 1 })).toEqual({ from: 0, to: 1 });
    expect(rangeOf(text, { line: 1, col: 5, end_line: 1, end_col: 2 })).toEqual({ from: 4, to: 5 });
    expect(rangeOf(text, {})).toEqual({ from: 0, to: 1 });
  });
});
