import { describe, expect, it } from "vitest";
import { formatAge, linkHealth } from "./linkHealth";

const up = { rttMs: 1, measuredBytesPerS: 10, plannedBytesPerS: 10, lastFrameAgeS: 0.2, connected: true, state: "up" };

describe("linkHealth", () => {
  it("is up with fresh frames, unknown before any status", () => {
    expect(linkHealth({ stream: "open", status: up, statusAt: 100, now: 101 }).down).toBe(false);
    expect(linkHealth({ stream: "connecting", status: null, statusAt: null, now: 1 })).toEqual({ down: false, reason: null, lastFrameAt: null });
  });

  it("is lost when the link is down, frames stop, statuses stop or the stream closes", () => {
    expect(linkHealth({ stream: "open", status: { ...up, connected: false, state: "connecting" }, statusAt: 100, now: 100 }).reason).toBe("the base station is trying to reach the drone");
    // the session's state names are not the reason's words ("link handshake" said nothing to an operator)
    for (const state of ["handshake", "down", "stopped", undefined] as const) {
      const reason = linkHealth({ stream: "open", status: { ...up, connected: false, state }, statusAt: 100, now: 100 }).reason ?? "";
      expect(reason).toMatch(/drone|base station/);
      expect(reason).not.toMatch(/^link /);
    }
    const stale = linkHealth({ stream: "open", status: { ...up, lastFrameAgeS: 4 }, statusAt: 100, now: 102 });
    expect(stale).toEqual({ down: true, reason: "no frame from the drone for 6 s", lastFrameAt: 96 });
    expect(linkHealth({ stream: "open", status: up, statusAt: 100, now: 112 }).reason).toBe("no status from the base station for 12 s");
    expect(linkHealth({ stream: "closed", status: up, statusAt: 100, now: 100 }).down).toBe(true);
  });

  it("formats ages", () => {
    expect([formatAge(4.4), formatAge(184), formatAge(7500)]).toEqual(["4 s", "3 min 4 s", "2 h 5 min"]);
  });
});
