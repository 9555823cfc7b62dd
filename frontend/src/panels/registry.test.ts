import { describe, expect, it } from "vitest";
import { PANELS, panelTabs } from "./registry";

const ids = (campaign: boolean, active: Parameters<typeof panelTabs>[1]) => panelTabs(campaign, active).map((p) => p.id);

describe("the dock's tabs", () => {
  it("show the Fleet panel for a campaign only", () => {
    expect(ids(true, "monitor")).toContain("fleet");
    expect(ids(false, "monitor")).not.toContain("fleet");
    expect(ids(false, "monitor")).toHaveLength(PANELS.length - 1);
  });

  it("keep the Fleet tab while it is the panel shown (a campaign edited back to one drone)", () => {
    expect(ids(false, "fleet")).toContain("fleet");
  });
});
