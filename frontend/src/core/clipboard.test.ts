import { describe, expect, it } from "vitest";
import { copyElements, pasteFragment, PASTE_OFFSET } from "./clipboard";
import { moveNodes } from "./ops";
import { scenario1 } from "./testing/scenario1";

describe("copy/paste", () => {
  it("pastes subscribers under free names, shifted", () => {
    const m = moveNodes(scenario1(), { "sub:sub_1": { x: 100, y: 100 } });
    const f = copyElements(m, ["sub:sub_1", "sub:sub_2", "drone"]);
    const r = pasteFragment(m, f);
    expect(r.ids).toEqual(["sub:sub_1_copy", "sub:sub_2_copy"]);
    expect(r.model.subscribers).toHaveLength(9);
    expect(r.model.subscribers[7]).toMatchObject({ name: "sub_1_copy", topic: "usv.accelerometer.accel_x", periodS: "2.0" });
    expect(r.model.layout?.nodes?.["sub:sub_1_copy"]).toEqual({ x: 100 + PASTE_OFFSET, y: 100 + PASTE_OFFSET });
    // Pasting again finds the next free name.
    expect(pasteFragment(r.model, f).ids[0]).toBe("sub:sub_1_copy_2");
  });

  it("pastes a sensor with a publisher: references follow the new sensor", () => {
    const m = scenario1();
    const f = copyElements(m, ["sensor:accelerometer", "pub:pub_1"]);
    const r = pasteFragment(m, f);
    expect(r.model.drone.sensors.map((s) => s.name)).toEqual(["accelerometer", "accelerometer_copy"]);
    expect(r.model.publishers[1].topics).toEqual([
      "usv.accelerometer_copy.accel_x", "usv.accelerometer_copy.accel_y", "usv.accelerometer_copy.accel_z",
    ]);
  });
});
