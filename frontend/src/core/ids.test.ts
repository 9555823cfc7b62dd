import { describe, expect, it } from "vitest";
import { parseId, publisherId, sensorId, splitTopicName, subscriberId, topicId } from "./ids";

describe("element ids", () => {
  it("round-trips every kind", () => {
    expect(parseId(sensorId("gps"))).toEqual({ kind: "sensor", name: "gps", sensor: "gps" });
    expect(parseId(topicId("gps", "lat"))).toEqual({ kind: "topic", name: "gps.lat", sensor: "gps", variable: "lat" });
    expect(parseId(publisherId("p"))?.kind).toBe("publisher");
    expect(parseId(subscriberId("s"))?.kind).toBe("subscriber");
    for (const id of ["drone", "pubBroker", "subBroker", "link"]) expect(parseId(id)?.kind).toBe(id);
  });

  it("rejects malformed ids", () => {
    for (const id of ["", "sensor:", "topic:gps", "topic:.x", "topic:gps.", "what:x", "nothing"]) {
      expect(parseId(id)).toBeNull();
    }
  });

  it("splits topic names into three parts only", () => {
    expect(splitTopicName("usv.acc.x")).toEqual({ drone: "usv", sensor: "acc", variable: "x" });
    expect(splitTopicName("usv.acc")).toBeNull();
    expect(splitTopicName("usv..x")).toBeNull();
  });
});
