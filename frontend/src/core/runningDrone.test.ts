import { describe, expect, it } from "vitest";
import { runningHint } from "./runningDrone";
import { emptyModel } from "./templates";
import { scenario1 } from "./testing/scenario1";
import { initialState, reduce, currentModel } from "./workbench";

const moved = [{ drone: "usv", project_id: 1, revision: 1,
  pub_broker: { host: "127.0.0.1", port: 7181 }, sub_broker: { host: "127.0.0.1", port: 7282 } }];

describe("runningHint", () => {
  it("names the running drone's ports in an empty project and sets them", () => {
    const hint = runningHint(emptyModel(), moved)!;
    expect(hint.text).toBe("The running drone usv uses PubBroker 127.0.0.1:7181 and SubBroker 127.0.0.1:7282.");
    const s = hint.edits.reduce((st, e) => reduce(st, { type: "setField", ...e }), initialState(emptyModel(), "designer"));
    expect(currentModel(s).pubBroker.endpoint).toEqual({ host: "127.0.0.1", port: 7181 });
    expect(currentModel(s).subBroker.endpoint).toEqual({ host: "127.0.0.1", port: 7282 });
    expect(runningHint(currentModel(s), moved)!.edits).toEqual([]); // nothing left to change
  });

  it("says nothing for a project with content or without a running drone", () => {
    expect(runningHint(scenario1(), moved)).toBeNull();
    expect(runningHint(emptyModel(), [])).toBeNull();
    expect(runningHint(emptyModel(), [{ ...moved[0], pub_broker: null, sub_broker: null }])).toBeNull();
  });
});
