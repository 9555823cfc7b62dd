import { describe, expect, it } from "vitest";
import { applyCampaignEdit, campaignEditKey } from "./campaign";
import { campaignDiagnostics, campaignPointer, messagesAt, messagesElsewhere } from "./campaignForm";
import { MODD_SCHEMA } from "./schema";
import { EditError } from "./ops";
import { scenario1 } from "./testing/scenario1";
import type { ModdModel } from "./model.gen";

const started = (): ModdModel => applyCampaignEdit(scenario1(), { op: "start" });

describe("campaign edits", () => {
  it("start with two vehicles, the second on a PubBroker endpoint of its own, and leave the input unchanged", () => {
    const one = scenario1();
    const m = applyCampaignEdit(one, { op: "start" });
    expect(one.campaign).toBeUndefined();
    expect(m.campaign?.vehicles.map((v) => v.pubBroker?.endpoint.port)).toEqual([undefined, 7172]);
    const more = applyCampaignEdit(applyCampaignEdit(m, { op: "addVehicle" }), { op: "addVehicle" });
    expect(more.campaign?.vehicles.map((v) => v.pubBroker?.endpoint.port)).toEqual([undefined, 7172, 7173, 7174]);
    expect(() => applyCampaignEdit(m, { op: "start" })).toThrow(EditError);
  });

  it("rename a channel in its vehicles, drop it from them when removed, keep one vehicle at least", () => {
    let m = applyCampaignEdit(started(), { op: "addChannel" });
    m = applyCampaignEdit(m, { op: "set", path: ["vehicles", "1", "channel"], value: "ch_1" });
    m = applyCampaignEdit(m, { op: "set", path: ["channels", "0", "name"], value: "lake" });
    expect(m.campaign?.vehicles[1].channel).toBe("lake");
    m = applyCampaignEdit(m, { op: "removeChannel", index: 0 });
    expect(m.campaign?.vehicles[1].channel).toBeUndefined();
    expect(m.campaign?.channels).toBeUndefined();
    m = applyCampaignEdit(m, { op: "removeVehicle", index: 0 });
    expect(() => applyCampaignEdit(m, { op: "removeVehicle", index: 0 })).toThrow(/at least one vehicle/);
  });

  it("remove a cleared setting and the broker it leaves empty; one undo step per field", () => {
    let m = applyCampaignEdit(started(), { op: "set", path: ["vehicles", "0", "subBroker", "endpoint", "port"], value: 7300 });
    expect(m.campaign?.vehicles[0].subBroker).toEqual({ endpoint: { port: 7300 } });
    m = applyCampaignEdit(m, { op: "set", path: ["vehicles", "0", "subBroker", "endpoint", "port"], value: undefined });
    expect(m.campaign?.vehicles[0]).toEqual({ name: "usv_1" });
    expect(campaignEditKey({ op: "set", path: ["name"], value: "x" })).toBe("campaign:name");
    expect(campaignEditKey({ op: "addVehicle" })).toBeUndefined();
  });
});

describe("campaign diagnostics", () => {
  it("check the campaign's fields as typed, located at each field", () => {
    const m = applyCampaignEdit(started(), { op: "set", path: ["vehicles", "1", "pubBroker", "endpoint", "port"], value: 70000 });
    const found = campaignDiagnostics(m, MODD_SCHEMA);
    expect(found.map((d) => d.pointer)).toEqual(["/campaign/vehicles/1/pubBroker/endpoint/port"]);
    expect(messagesAt(found, "/campaign/vehicles/1/pubBroker")).toHaveLength(1);
    expect(messagesAt(found, "/campaign/vehicles/1/pub")).toHaveLength(0); // segments, not characters
    expect(messagesElsewhere(found, "/campaign/vehicles/1", ["/campaign/vehicles/1/pubBroker"])).toEqual([]);
    expect(campaignPointer(["vehicles", 0, "a/b~"])).toBe("/campaign/vehicles/0/a~1b~0");
  });
});
