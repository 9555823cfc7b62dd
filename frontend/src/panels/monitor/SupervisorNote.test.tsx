// @vitest-environment jsdom
import { afterEach, describe, expect, it } from "vitest";
import { cleanup, render, screen } from "@testing-library/react";
import { SupervisorNote } from "./SupervisorNote";
import { toLinkStatus } from "../../dataSources/WebSocketSource";
import { linkHealth } from "../../core/linkHealth";
import type { SubBrokerStatus } from "../../core/contracts.gen";

afterEach(cleanup);

/** The status `modd up` puts when it gives up (launcher/src/modd_launch/announce.py). */
const stopped = (supervisor: unknown): Partial<SubBrokerStatus> => ({
  drone: "usv", time_ns: 1_700_000_000_000_000_000, link: "stopped", last_error: "x", supervisor,
});
const gaveUp = {
  state: "GAVE_UP", process: "subbroker", exit_code: 1, log: "/var/lib/modd/usv/subbroker.log",
  reason: "subbroker exited (1); stopping the run: 5 restarts within 300 s", at_ns: 1,
};

describe("SupervisorNote", () => {
  it("tells the operator which process stopped the run, why and where its log is", () => {
    const link = toLinkStatus(stopped(gaveUp));
    expect(link.gaveUp).toEqual({ process: "subbroker", exitCode: 1, reason: gaveUp.reason, log: gaveUp.log });
    render(<SupervisorNote stop={link.gaveUp!} />);
    const note = screen.getByRole("alert", { name: "Run stopped" });
    expect(note.textContent).toContain("modd up gave up the run: subbroker exited (1); stopping the run: 5 restarts within 300 s");
    expect(note.textContent).toContain("/var/lib/modd/usv/subbroker.log");
  });

  it("is the link's reason, even once no status follows the last one", () => {
    const status = toLinkStatus(stopped(gaveUp));
    for (const now of [100, 1000]) {  // 900 s after the last status: still the supervisor's reason
      expect(linkHealth({ stream: "open", status, statusAt: 100, now }).reason).toBe(`modd up gave up the run: ${gaveUp.reason}`);
    }
    const noReason = toLinkStatus(stopped({ ...gaveUp, reason: "" }));
    expect(linkHealth({ stream: "open", status: noReason, statusAt: 1, now: 1 }).reason).toBe("modd up gave up the run: subbroker exited (1)");
  });

  it("takes no other supervisor state, and shows a hostile reason as printable bounded text", () => {
    expect(toLinkStatus(stopped({ ...gaveUp, state: "RUNNING" })).gaveUp).toBeUndefined();
    expect(toLinkStatus(stopped("GAVE_UP")).gaveUp).toBeUndefined();
    expect(toLinkStatus({ link: "up" }).gaveUp).toBeUndefined();
    const hostile = toLinkStatus(stopped({ ...gaveUp, reason: "\u001b[31mred\u001b[0m\n<script>x</script>" + "a".repeat(1000) }));
    for (const c of ["\u001b", "\n"]) expect(hostile.gaveUp!.reason).not.toContain(c);
    expect(hostile.gaveUp!.reason.length).toBeLessThanOrEqual(300);
    render(<SupervisorNote stop={hostile.gaveUp!} />);
    expect(document.querySelector("script")).toBeNull();
    expect(screen.getByTestId("supervisor-stop").textContent).toContain("<script>x</script>");
  });
});
