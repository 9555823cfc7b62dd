import { describe, expect, it } from "vitest";
import { offsetOf } from "./positions";

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
