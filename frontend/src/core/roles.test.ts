import { describe, expect, it } from "vitest";
import { canDeploy, canEdit, canEditEdge, viewsFor, type Role } from "./roles";
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
    expect(viewsFor(["admin"])).toEqual(["designer", "integrator", "scientist", "operator"]);
    expect(viewsFor(["scientist", "operator"])).toEqual(["scientist", "operator"]);
  });
});
