import { describe, expect, it } from "vitest";
import { canonicalDecimal, canonicalJson, decimalFields, sameMeaning } from "./canonical";

describe("canonical values", () => {
  it("spells decimals as the .modd parser does", () => {
    // modd_model/numbers.py canonical_decimal's own examples, and more
    const cases: Array<[string, string | null]> = [
      [".5", "0.5"], ["2", "2.0"], ["0.250", "0.25"], ["4.0E-2", "0.04"], ["5", "5.0"], ["05.50", "5.5"],
      ["0", "0.0"], ["1e3", "1000.0"], ["1.", "1.0"], ["12.5e-3", "0.0125"], ["abc", null], ["-1", null], ["", null],
    ];
    for (const [text, want] of cases) expect(canonicalDecimal(text), text).toBe(want);
  });
  it("finds the decimal fields in the schema", () => {
    expect([...decimalFields()].sort()).toEqual([
      "acceptedDelayS", "alpha", "batteryWh", "beta", "dutyCycle", "expectedRttS", "idleW", "maxGapS", "periodS", "pingS", "rxW",
      "txW",
    ]);
  });
  it("compares by meaning: key order and decimal spelling aside, names untouched", () => {
    expect(sameMeaning({ name: "a", periodS: "5" }, { periodS: "5.0", name: "a" })).toBe(true);
    expect(sameMeaning({ name: "5" }, { name: "5.0" })).toBe(false);
    expect(canonicalJson({ b: [{ periodS: ".5" }], a: 1 })).toBe('{"a":1,"b":[{"periodS":"0.5"}]}');
  });
});
