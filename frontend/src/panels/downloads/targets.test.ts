import { describe, expect, it } from "vitest";
import { TARGETS } from "./targets";

describe("download titles", () => {
  it("name every language a role's zip holds", () => {
    // the integrator's zip: integrator/<publisher>-driver (C++), integrator/python
    // (publisher stubs) and integrator/ros2 (message package)
    const integrator = TARGETS.find((t) => t.target === "integrator")?.title ?? "";
    expect(integrator).toMatch(/C\+\+/);
    expect(integrator).toMatch(/Python/);
    expect(integrator).toMatch(/ROS 2/);
    expect(TARGETS.find((t) => t.target === "scientist")?.title).toMatch(/Python.*C\+\+/);
  });
});
