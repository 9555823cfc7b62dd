import { describe, expect, it } from "vitest";
import { courseDeg, defaultColour } from "./marker";

describe("vehicle marker", () => {
  it("heads along the last move, clockwise from north", () => {
    expect(courseDeg([{ east: 0, north: 0 }, { east: 0, north: 5 }])).toBeCloseTo(0);
    expect(courseDeg([{ east: 0, north: 0 }, { east: 5, north: 0 }])).toBeCloseTo(90);
    expect(courseDeg([{ east: 0, north: 0 }, { east: -3, north: -3 }])).toBeCloseTo(225);
    // a fix repeated (the drone held still) looks further back
    expect(courseDeg([{ east: 0, north: 0 }, { east: 0, north: -4 }, { east: 0, north: -4 }])).toBeCloseTo(180);
    expect(courseDeg([{ east: 1, north: 1 }])).toBeNull();
  });

  it("colours by a value of the place, not the drone's own motion, at first", () => {
    const choices = [
      { channel: "sub_1", unit: "m/s²" }, { channel: "roll", unit: "rad" },
      { channel: "water_temp", unit: "°C" }, { channel: "cond", unit: "mS/cm" },
    ];
    expect(defaultColour(choices)).toBe("water_temp");
    expect(defaultColour(choices.slice(0, 2))).toBe("sub_1");
    expect(defaultColour([])).toBe("");
  });
});
