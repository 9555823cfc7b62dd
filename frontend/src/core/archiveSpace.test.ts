import { describe, expect, it } from "vitest";
import { archiveSpace, formatHours } from "./archiveSpace";

describe("archiveSpace", () => {
  it("gives the hours left at the current rate", () => {
    const s = archiveSpace({ disk_free_mb: 1024, archive_rate_bps: 2048, archive_state: 0 })!;
    expect(s.state).toBe("ok");
    expect(s.hoursLeft).toBeCloseTo((1024 * 1048576) / 2048 / 3600, 6);
    expect(s.warn).toBe(false);
  });

  it("warns on low space, a full disk, or under two hours left", () => {
    expect(archiveSpace({ disk_free_mb: 200, archive_rate_bps: 10, archive_state: 1 })!.warn).toBe(true);
    expect(archiveSpace({ disk_free_mb: 0, archive_rate_bps: 0, archive_state: 2 })!.state).toBe("full");
    const soon = archiveSpace({ disk_free_mb: 10, archive_rate_bps: 4096, archive_state: 0 })!;
    expect(soon.hoursLeft!).toBeLessThan(1);
    expect(soon.warn).toBe(true);
  });

  it("knows nothing without the PubBroker's counters, and no end when nothing is written", () => {
    expect(archiveSpace({})).toBeNull();
    expect(archiveSpace(undefined)).toBeNull();
    expect(archiveSpace({ disk_free_mb: 500, archive_rate_bps: 0, archive_state: 0 })!.hoursLeft).toBeNull();
  });

  it("formats hours for people", () => {
    expect(formatHours(3.34)).toBe("3 h 20 min");
    expect(formatHours(0.75)).toBe("45 min");
    expect(formatHours(300)).toBe("12 days");
  });
});
