import { describe, expect, it } from "vitest";
import { listTopics, pointerOf, pointerTarget } from "./query";
import { scenario1 } from "./testing/scenario1";

describe("pointers ↔ elements", () => {
  const m = scenario1();

  it("lists topics with their qualified names", () => {
    expect(listTopics(m).map((t) => t.name)).toEqual([
      "usv.accelerometer.accel_x", "usv.accelerometer.accel_y", "usv.accelerometer.accel_z",
    ]);
  });

  it("maps field pointers to elements and fields", () => {
    expect(pointerTarget(m, "/subscribers/2/periodS")).toEqual({ id: "sub:sub_3", field: ["periodS"] });
    expect(pointerTarget(m, "/drone/sensors/0/variables/2/unit")).toEqual({ id: "topic:accelerometer.accel_z", field: ["unit"] });
    expect(pointerTarget(m, "/drone/sensors/0/name")).toEqual({ id: "sensor:accelerometer", field: ["name"] });
    expect(pointerTarget(m, "/pubBroker/endpoint/port")).toEqual({ id: "pubBroker", field: ["endpoint", "port"] });
    expect(pointerTarget(m, "/link/pingS")).toEqual({ id: "link", field: ["pingS"] });
    expect(pointerTarget(m, "/publishers/0/topics/1")).toEqual({ id: "pub:pub_1", field: ["topics", "1"] });
  });

  it("falls back to the drone for root and out-of-range pointers", () => {
    expect(pointerTarget(m, "").id).toBe("drone");
    expect(pointerTarget(m, "/subscribers/99").id).toBe("drone");
    expect(pointerTarget(m, "/drone/sensors/7/name").id).toBe("drone");
  });

  it("gives the pointer of each element, inverse of pointerTarget", () => {
    for (const id of ["sub:sub_7", "pub:pub_1", "topic:accelerometer.accel_y", "sensor:accelerometer", "drone", "pubBroker"]) {
      const p = pointerOf(m, id);
      expect(p).not.toBeNull();
      expect(pointerTarget(m, p!).id).toBe(id);
    }
    expect(pointerOf(m, "sub:nobody")).toBeNull();
  });
});
