import { describe, expect, it } from "vitest";
import { canDeploy, canEdit, canEditEdge, canFillGaps, deniedParts, viewsFor, type Role } from "./roles";
import type { ElementKind } from "./ids";

const KINDS: ElementKind[] = ["drone", "sensor", "topic", "pubBroker", "subBroker", "link", "publisher", "subscriber"];

describe("role permissions", () => {
  const matrix: Record<Exclude<Role, "admin">, ElementKind[]> = {
    designer: ["drone", "pubBroker", "subBroker", "link", "publisher"],
    integrator: ["sensor", "topic"],
    scientist: ["subscriber"],
    operator: [],
  };

  it.each(Object.entries(matrix))("%s edits exactly its elements", (role, kinds) => {
    for (const k of KINDS) expect(canEdit(role as Role, k), `${role} ${k}`).toBe(kinds.includes(k));
  });

  it("gives admin everything", () => {
    for (const k of KINDS) expect(canEdit("admin", k)).toBe(true);
    expect(canDeploy("admin")).toBe(true);
  });

  it("lets the scientist and the operator fill gaps", () => {
    expect(["designer", "integrator", "scientist", "operator", "admin"].filter((r) => canFillGaps(r as Role))).toEqual(["scientist", "operator", "admin"]);
  });

  it("lets only operators deploy", () => {
    expect(["designer", "integrator", "scientist", "operator"].filter((r) => canDeploy(r as Role))).toEqual(["operator"]);
  });

  it("gives edges to their owners and structure to nobody", () => {
    expect(canEditEdge("designer", "publishes")).toBe(true);
    expect(canEditEdge("scientist", "publishes")).toBe(false);
    expect(canEditEdge("scientist", "subscribes")).toBe(true);
    expect(canEditEdge("admin", "measures")).toBe(false);
  });

  it("lists views for a user's roles", () => {
    expect(viewsFor(["admin"])).toEqual(["designer", "integrator", "scientist", "operator", "admin"]); // All roles last
    expect(viewsFor(["scientist", "operator"])).toEqual(["scientist", "operator"]);
  });
});

describe("deniedParts (the backend's save rule)", () => {
  it("names the parts a role does not own", async () => {
    const { scenario1 } = await import("./testing/scenario1");
    const { rename, moveNodes } = await import("./ops");
    const before = scenario1();
    // Renaming a sensor changes the integrator's part and, by reference, the designer's and the scientist's.
    const after = rename(before, "sensor:accelerometer", "imu");
    expect(deniedParts("integrator", before, after)).toEqual(["/publishers", "/subscribers"]);
    expect(deniedParts("admin", before, after)).toEqual([]);
    const moved = moveNodes(before, { drone: { x: 1, y: 2 } });
    expect(deniedParts("scientist", before, moved)).toEqual([]);
    expect(deniedParts("operator", before, moved)).toEqual(["/layout"]);
    const renamedDrone = rename(before, "drone", "auv");
    expect(deniedParts("designer", before, renamedDrone)).toEqual(["/subscribers"]);
  });
});
