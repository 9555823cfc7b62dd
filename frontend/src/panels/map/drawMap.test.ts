import { describe, expect, it } from "vitest";
import { tileOrigin, tileUrlProblem } from "./drawMap";

describe("tile URL", () => {
  it("takes an http(s) template with {z}, {x} and {y}, and says what is wrong otherwise", () => {
    expect(tileUrlProblem("")).toBeNull();
    expect(tileUrlProblem("https://tile.openstreetmap.org/{z}/{x}/{y}.png")).toBeNull();
    expect(tileUrlProblem("https://tile.openstreetmap.org/{z}/{x}.png")).toBe("a tile URL needs {y}");
    expect(tileUrlProblem("ftp://tiles/{z}/{x}/{y}")).toMatch(/http/);
    expect(tileUrlProblem("javascript:alert(1)//{z}{x}{y}")).toMatch(/http/);
    expect(tileUrlProblem("http://a b/{z}/{x}/{y}")).toBe("not a URL");
    expect(tileOrigin("http://127.0.0.1:8123/{z}/{x}/{y}.png")).toBe("http://127.0.0.1:8123");
  });
});
