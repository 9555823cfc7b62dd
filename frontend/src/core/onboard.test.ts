import { describe, expect, it } from "vitest";
import { onboardLines } from "./onboard";

describe("onboardLines", () => {
  it("says each instrument's action and a missing device", () => {
    const lines = onboardLines({
      sensors: { ok: false, sensors: [
        { sensor: "gnss", action: "unchanged", ok: true, state: "open" },
        { sensor: "echo", action: "started", ok: false, state: "closed", problem: "device /dev/ttyX missing" },
        { sensor: "old", action: "stopped", ok: true, state: "closed" },
      ] },
      mavlink: { ok: true, added: ["usv.autopilot.pitch"], removed: [], changed: [] },
    });
    expect(lines).toEqual([
      { process: "mavlink", ok: true, text: "added usv.autopilot.pitch" },
      { process: "sensors", ok: false, text: "gnss unchanged (open); echo started — device /dev/ttyX missing; old stopped" },
    ]);
  });

  it("leaves out, when asked, the instruments a deploy did not touch", () => {
    const onboard = { sensors: { ok: true, sensors: [
      { sensor: "gnss", action: "unchanged", ok: true, state: "open" },
      { sensor: "gps2", action: "started", ok: true, state: "open" },
    ] } };
    expect(onboardLines(onboard, true)[0].text).toBe("gps2 started (open)");
  });

  it("reads an invalid model's refusal and hostile shapes without failing", () => {
    expect(onboardLines({ sensors: { ok: false, problem: "invalid model: x" } })[0].text).toBe("invalid model: x");
    expect(onboardLines(null)).toEqual([]);
    expect(onboardLines([1, 2])).toEqual([]);
    expect(onboardLines({ a: 3, b: { ok: true, sensors: "x" } })).toEqual([{ process: "b", ok: true, text: "applied" }]);
  });
});
