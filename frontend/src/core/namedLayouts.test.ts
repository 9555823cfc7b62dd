import { describe, expect, it } from "vitest";
import { deleteNamed, layoutFile, layoutFileName, listNamed, MAX_NAMED, parseLayoutFile, saveNamed, type NamedLayout } from "./namedLayouts";

function memory() {
  const m = new Map<string, string>();
  return { getItem: (k: string) => m.get(k) ?? null, setItem: (k: string, v: string) => void m.set(k, v), removeItem: (k: string) => void m.delete(k) };
}
const PANELS = ["plan", "monitor", "map"];
const three: NamedLayout = { panel: "monitor", layout: { beside: ["map", "plan"], stacked: false, sizes: [0.5, 0.3, 0.2], height: 420 } };

describe("named layouts", () => {
  it("are kept per user and role, replaced by name and deleted", () => {
    const s = memory();
    expect(saveNamed(s, "ana", "scientist", " Survey ", three, PANELS)).toBeNull();
    expect(listNamed(s, "ana", "scientist", PANELS)).toEqual({ Survey: three });
    expect(listNamed(s, "ana", "operator", PANELS)).toEqual({});
    expect(listNamed(s, "bob", "scientist", PANELS)).toEqual({});
    const two = { ...three, layout: { ...three.layout, beside: ["map" as const], sizes: [0.6, 0.4] } };
    saveNamed(s, "ana", "scientist", "Survey", two, PANELS);
    expect(listNamed(s, "ana", "scientist", PANELS).Survey).toEqual(two);
    deleteNamed(s, "ana", "scientist", "Survey", PANELS);
    expect(listNamed(s, "ana", "scientist", PANELS)).toEqual({});
  });

  it("refuses an empty or long name and more than the most kept", () => {
    const s = memory();
    expect(saveNamed(s, "ana", "op", "  ", three, PANELS)).toMatch(/needs a name/);
    expect(saveNamed(s, "ana", "op", "x".repeat(61), three, PANELS)).toMatch(/at most 60 characters/);
    for (let i = 0; i < MAX_NAMED; i += 1) expect(saveNamed(s, "ana", "op", `L${i}`, three, PANELS)).toBeNull();
    expect(saveNamed(s, "ana", "op", "one more", three, PANELS)).toMatch(/delete one first/);
    expect(saveNamed(s, "ana", "op", "L3", three, PANELS)).toBeNull(); // replacing is fine
  });

  it("leaves out stored entries it cannot read", () => {
    const s = memory();
    s.setItem("modd.layouts.ana.op", JSON.stringify({ ok: three, bad: { panel: "nope", layout: {} }, "": three }));
    expect(Object.keys(listNamed(s, "ana", "op", PANELS))).toEqual(["ok"]);
    s.setItem("modd.layouts.ana.op", "{not json");
    expect(listNamed(s, "ana", "op", PANELS)).toEqual({});
  });

  it("round-trips through its file", () => {
    const text = layoutFile("Survey", "scientist", three);
    expect(JSON.parse(text).format).toBe("modd-dock-layout");
    expect(parseLayoutFile(text, PANELS)).toEqual({ name: "Survey", named: three });
    expect(layoutFileName("Survey / night")).toBe("Survey_night.modd-layout.json");
  });

  it("refuses a bad file with the field that is wrong", () => {
    const good = JSON.parse(layoutFile("Survey", "scientist", three));
    const bad = (patch: object) => {
      const r = parseLayoutFile(JSON.stringify({ ...good, ...patch }), PANELS);
      return "error" in r ? r.error : "accepted";
    };
    expect((parseLayoutFile("{", PANELS) as { error: string }).error).toMatch(/^not JSON/);
    expect(bad({ format: "foxglove" })).toMatch(/not a MoDD layout file/);
    expect(bad({ version: 2 })).toMatch(/`version` is 2/);
    expect(bad({ name: "" })).toMatch(/`name`: a layout needs a name/);
    expect(bad({ panel: "radar" })).toMatch(/`panel` is "radar", not a panel/);
    expect(bad({ layout: { ...good.layout, beside: ["map", "radar"] } })).toMatch(/`layout.beside\[1\]` is "radar"/);
    expect(bad({ layout: { ...good.layout, beside: ["map", "map"] } })).toMatch(/names a panel twice/);
    expect(bad({ layout: { ...good.layout, sizes: [1] } })).toMatch(/`layout.sizes` is not 3 positive numbers/);
    expect(bad({ layout: { ...good.layout, height: 5000 } })).toMatch(/`layout.height`/);
    expect(bad({ layout: { ...good.layout, stacked: "yes" } })).toMatch(/`layout.stacked`/);
    expect((parseLayoutFile(" ".repeat(70000), PANELS) as { error: string }).error).toMatch(/at most 65536/);
  });
});
