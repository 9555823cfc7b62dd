/**
 * Gaps and backfilled values on the Monitor's charts: the source keeps a
 * backfilled window in place (time order, never doubled), the chart data
 * break a line where windows are missing and mark the backfilled points,
 * and the caption counts both.
 */
import { describe, expect, it } from "vitest";
import { RingBuffer } from "../../dataSources/RingBuffer";
import { WebSocketSource, type SocketLike } from "../../dataSources/WebSocketSource";
import type { Sample } from "../../dataSources/types";
import { alignWithGaps, findGaps, gapSummary, liveGaps } from "../../core/chartData";
import { sumProgress } from "./FillGaps";

class FakeSocket implements SocketLike {
  readyState = 1;
  onopen: SocketLike["onopen"] = null;
  onmessage: SocketLike["onmessage"] = null;
  onclose: SocketLike["onclose"] = null;
  onerror: SocketLike["onerror"] = null;
  send() {}
  close() {}
  deliver(msg: object) { this.onmessage?.({ data: JSON.stringify(msg) }); }
}

/** A delivered value of a 1 s AVERAGE window ending at `end` s. */
const win = (end: number, value: number, backfilled = false) => ({
  type: "value", subscriber: "sub_5",
  data: { start_ns: (end - 1) * 1e9, end_ns: end * 1e9, value, count: 4, ...(backfilled ? { backfilled: true } : {}) },
});

describe("RingBuffer.insertOrdered", () => {
  it("matches sorting everything and keeping the newest `capacity` (random order, duplicates replaced)", () => {
    let seed = 7;
    const rand = () => ((seed = (seed * 1103515245 + 12345) % 2 ** 31) / 2 ** 31);
    for (let round = 0; round < 50; round++) {
      const cap = 1 + Math.floor(rand() * 12);
      const r = new RingBuffer<{ k: number; id: number }>(cap);
      let oracle: Array<{ k: number; id: number }> = [];
      let dropped = 0;
      for (let id = 0; id < 40; id++) {
        // mostly ascending (live), sometimes older (backfilled)
        const k = rand() < 0.7 ? id : Math.floor(rand() * id);
        const item = { k, id };
        r.insertOrdered(item, (x) => x.k, (a, b) => a.k === b.k);
        const at = oracle.findIndex((x) => x.k === k);
        if (at >= 0) { oracle[at] = item; continue; }
        oracle = [...oracle, item].sort((a, b) => a.k - b.k);
        if (oracle.length > cap) { oracle.shift(); dropped++; }
      }
      expect(r.toArray()).toEqual(oracle);
      expect(r.dropped).toBe(dropped);
    }
  });
});

describe("backfilled values in the source", () => {
  it("go in place among the live ones, keep their mark, and never double nor replace a live window", () => {
    const sock = new FakeSocket();
    const src = new WebSocketSource({ url: "ws://127.0.0.1/x", connect: () => sock, capacity: 100 });
    const got: Sample[][] = [];
    src.subscribe("sub_5", (b) => got.push([...b]));
    for (const t of [1, 2, 3, 7, 8]) sock.deliver(win(t, t * 10));
    for (const t of [4, 5, 6]) sock.deliver(win(t, t * 10 + 1, true));
    sock.deliver(win(3, 30, true)); // a window the link did deliver: not twice, the live one kept
    const h = src.history("sub_5");
    expect(h.map((s) => s.t)).toEqual([1, 2, 3, 4, 5, 6, 7, 8]);
    expect(h.filter((s) => s.backfilled).map((s) => s.t)).toEqual([4, 5, 6]);
    expect(h.find((s) => s.t === 5)?.value).toBe(51);
    expect(got.at(-1)?.[0].backfilled).toBe(true);
  });
});

describe("gaps on a chart", () => {
  const live = (ts: number[]): Sample[] => ts.map((t) => ({ t, value: t }));

  it("finds the missing windows from the subscription's period", () => {
    expect(findGaps(live([1, 2, 3, 7, 8]), 1)).toEqual([[3, 7, 3]]);
    expect(findGaps(live([1, 2, 3, 7, 8]), undefined)).toEqual([]);
    // half-second windows with jitter: no gap
    expect(findGaps(live([0.5, 1.02, 1.49, 2.01]), 0.5)).toEqual([]);
  });

  it("breaks the line inside a gap (null) but joins across another channel's points (undefined)", () => {
    const [xs, a, aMarked, b] = alignWithGaps([
      { samples: live([1, 2, 3, 7, 8]), periodS: 1 },
      { samples: [{ t: 2.5, value: 9 }, { t: 3.5, value: 9 }], periodS: 1 },
    ]);
    expect(xs).toEqual([1, 2, 2.5, 3, 3.5, 4, 7, 8]);
    expect(a).toEqual([1, 2, undefined, 3, undefined, null, 7, 8]);
    expect(aMarked.every((v) => v === undefined)).toBe(true);
    expect(b).toEqual([undefined, undefined, 9, undefined, 9, undefined, undefined, undefined]);
  });

  it("after a backfill: no gap, the filled points marked in place", () => {
    const filled = [...live([1, 2, 3]), ...[4, 5, 6].map((t) => ({ t, value: t, backfilled: true })), ...live([7, 8])];
    const [xs, line, marked] = alignWithGaps([{ samples: filled, periodS: 1 }]);
    expect(xs).toEqual([1, 2, 3, 4, 5, 6, 7, 8]);
    expect(line).not.toContain(null);
    expect(marked).toEqual([undefined, undefined, undefined, 4, 5, 6, undefined, undefined]);
    expect(gapSummary([{ samples: live([1, 2, 3, 7, 8, 11]), periodS: 1 }])).toBe("5 windows missing in 2 gaps · 0 backfilled");
    expect(gapSummary([{ samples: filled, periodS: 1 }])).toBe("no gap · 3 backfilled");
  });
});

describe("Fill gaps of several subscriptions", () => {
  it("sums the windows and bytes/s, runs while one runs, and says a failure", () => {
    const p = (status: string, done: number, total: number, left: number | null) => ({
      status, windows: done, windows_done: done, windows_total: total, duplicates: 0, bytes: 10, rate_bps: 600, seconds: 1, bytes_per_s: 100, seconds_left: left,
    });
    expect(sumProgress([p("DONE", 4, 4, null), p("RUNNING", 1, 6, 3)])).toMatchObject({ status: "RUNNING", windows_done: 5, windows_total: 10, bytes_per_s: 200, seconds_left: 3 }); // the one running job's own time left (no view of the queue)
    expect(sumProgress([p("DONE", 4, 4, null), p("DONE", 6, 6, null)])).toMatchObject({ status: "DONE", windows: 10 });
    expect(sumProgress([p("ERROR", 0, 0, null), { ...p("ERROR", 0, 0, null), reason: "no link" }])).toMatchObject({ status: "ERROR" });
    expect(sumProgress([{ ...p("ERROR", 0, 0, null), reason: "no link" }])).toMatchObject({ status: "ERROR", reason: "no link" });
    // one refused, the others done: done (the refusal is said beside the bar)
    expect(sumProgress([p("DONE", 4, 4, null), { ...p("ERROR", 0, 0, null), reason: "no link" }])).toMatchObject({ status: "DONE", windows: 4 });
    expect(sumProgress([])).toBeNull();
  });
});

describe("gaps counted after a fill", () => {
  it("counts what the page missed live, not the stretch before it opened that a fill reaches back across", () => {
    // A fill brought windows 1–3 of the mission (before the page opened at 100); the page then
    // saw 100..110 every 2 s with 104 and 106 missing, then filled.
    const old = [1, 3, 5].map((t) => ({ t, value: 0, backfilled: true }));
    const live = [100, 102, 108, 110].map((t) => ({ t, value: 1 }));
    expect(gapSummary([{ samples: [...old, ...live], periodS: 2 }])).toBe("2 windows missing in 1 gap · 3 backfilled");
    const filled = [104, 106].map((t) => ({ t, value: 1, backfilled: true }));
    const all = [...old, ...live.slice(0, 2), ...filled, ...live.slice(2)];
    expect(gapSummary([{ samples: all, periodS: 2 }])).toBe("no gap · 5 backfilled");
    expect(liveGaps({ samples: old, periodS: 2 })).toEqual([]); // nothing live: its own gaps
  });
});
