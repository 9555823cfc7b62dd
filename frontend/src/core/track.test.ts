import { describe, expect, it } from "vitest";
import { colourOf, gridStep, headingSubscriber, positionPairs, positionSubscribers, positionTopics, trackPoints, valueAt, valueRange, withRecord } from "./track";
import { scenario1 } from "./testing/scenario1";

const s = (t: number, value: number) => ({ t, value });

describe("track", () => {
  it("finds the position subscriptions by variable name", () => {
    const m = scenario1();
    m.subscribers.push({ name: "la", topic: "usv.gps.latitude", periodS: "1", aggregation: "LAST" },
      { name: "lo", topic: "usv.gps.lon", periodS: "1", aggregation: "LAST" });
    expect(positionSubscribers(m)).toEqual({ lat: "la", lon: "lo" });
    expect(positionSubscribers(scenario1())).toEqual({ lat: null, lon: null });
  });

  it("finds the position topics of an archive by variable name", () => {
    expect(positionTopics(["usv.ctd.water_temperature", "usv.gps.longitude", "usv.gps.latitude"]))
      .toEqual({ lat: "usv.gps.latitude", lon: "usv.gps.longitude" });
    expect(positionTopics(["usv.gps.platitude"])).toEqual({ lat: null, lon: null });
  });

  it("pairs an archive's position topics by sensor, the one with the most fixes first", () => {
    const t = (topic: string, messages: number) => ({ topic, messages });
    expect(positionPairs([t("usv.gps.latitude", 9), t("usv.ctd.water_temperature", 50), t("usv.gps.longitude", 8),
      t("usv.gnss.lat", 40), t("usv.gnss.lon", 41)])).toEqual([
      { lat: "usv.gnss.lat", lon: "usv.gnss.lon", fixes: 40 },
      { lat: "usv.gps.latitude", lon: "usv.gps.longitude", fixes: 8 },
    ]);
    // no sensor with both: every latitude with every longitude
    expect(positionPairs([t("usv.a.lat", 3), t("usv.b.lon", 5)])).toEqual([{ lat: "usv.a.lat", lon: "usv.b.lon", fixes: 3 }]);
    expect(positionPairs([t("usv.a.lat", 3)])).toEqual([]);
  });

  it("pairs fixes and puts them in metres from the first (an independent figure: 1e-3° of latitude ≈ 111.2 m)", () => {
    const pts = trackPoints([s(1, 47.7), s(2, 47.701), s(3, 47.702)], [s(1, -3.35), s(2.1, -3.35), s(9, -3.349)], [s(0.5, 10), s(2.5, 14)]);
    expect(pts).toHaveLength(2);
    expect(pts[1].north).toBeCloseTo(111.19, 1);
    expect(pts[1].east).toBeCloseTo(0, 6);
    expect(pts.map((p) => p.value)).toEqual([10, 10]);
    expect(valueRange(pts)).toEqual([10, 10]);
  });

  it("reads a step value, colours and rounds the grid", () => {
    expect(valueAt([s(1, 5), s(3, 7)], 2)).toBe(5);
    expect(valueAt([s(1, 5)], 0)).toBeNull();
    expect(colourOf(0)).toEqual([0, 0, 255]);
    expect(colourOf(1)).toEqual([255, 0, 0]);
    expect(gridStep(400)).toBe(100);
  });
});

describe("the track since the mission began", () => {
  it("puts the record's fixes older than the live series' first before it", () => {
    const record: Array<[number, number, number]> = [[1, 44.1, -63.1], [2, 44.2, -63.2], [3, 44.3, -63.3]];
    const live = [{ t: 3, value: 44.3 }, { t: 4, value: 44.4 }];
    expect(withRecord(record, 1, live).map((s) => [s.t, s.value])).toEqual([[1, 44.1], [2, 44.2], [3, 44.3], [4, 44.4]]);
    expect(withRecord(record, 2, []).map((s) => s.value)).toEqual([-63.1, -63.2, -63.3]); // a reload: the record alone
    expect(withRecord([], 1, live)).toEqual(live);
    expect(withRecord([[1, 0, 0, 12.5], [2, 0, 0, null], [3, 0, 0]], 3, []).map((s) => [s.t, s.value])).toEqual([[1, 12.5]]);
  });

  it("points the vehicle along a heading or course topic when a subscription has one", () => {
    const m = scenario1();
    expect(headingSubscriber(m)).toBeNull();
    m.subscribers.push({ ...m.subscribers[0], name: "sub_hdg", topic: "usv.gps.course_true" });
    expect(headingSubscriber(m)).toBe("sub_hdg");
  });
});
