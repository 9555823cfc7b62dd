import { describe, expect, it, vi } from "vitest";
import { WebSocketSource, qcFlags, toLinkStatus, toSamples, withBatch, type SocketLike } from "./WebSocketSource";
import { flaggedSeries, qcSummary } from "../core/chartData";
import deliveredVectors from "../../../contracts/vectors/delivered_value.json";
import statusVectors from "../../../contracts/vectors/status.json";
import type { DeliveredValue, SubBrokerStatus } from "../core/contracts.gen";
import { RingBuffer } from "./RingBuffer";

class FakeSocket implements SocketLike {
  readyState = 0;
  sent: unknown[] = [];
  onopen: SocketLike["onopen"] = null;
  onmessage: SocketLike["onmessage"] = null;
  onclose: SocketLike["onclose"] = null;
  onerror: SocketLike["onerror"] = null;
  send(d: string) { this.sent.push(JSON.parse(d)); }
  close() { this.readyState = 3; this.onclose?.({}); }
  open() { this.readyState = 1; this.onopen?.({}); }
  deliver(msg: object) { this.onmessage?.({ data: JSON.stringify(msg) }); }
}

function setup(capacity = 10) {
  const sock = new FakeSocket();
  const src = new WebSocketSource({ url: "ws://127.0.0.1/x", connect: () => sock, capacity });
  return { sock, src };
}

describe("RingBuffer", () => {
  it("drops the oldest and counts", () => {
    const r = new RingBuffer<number>(3);
    for (let i = 1; i <= 5; i += 1) r.push(i);
    expect(r.toArray()).toEqual([3, 4, 5]);
    expect(r.dropped).toBe(2);
    expect(r.last()).toBe(5);
  });
});

describe("WebSocketSource", () => {
  it("subscribes once per channel, after the socket opens, and unsubscribes with the last listener", () => {
    const { sock, src } = setup();
    const off1 = src.subscribe("sub_1", () => {});
    const off2 = src.subscribe("sub_1", () => {});
    expect(sock.sent).toEqual([]);
    sock.open();
    expect(sock.sent).toEqual([{ op: "subscribe", subscriber: "sub_1" }]);
    off1();
    expect(sock.sent).toHaveLength(1);
    off2();
    expect(sock.sent).toEqual([{ op: "subscribe", subscriber: "sub_1" }, { op: "unsubscribe", subscriber: "sub_1" }]);
    expect(src.state).toBe("open");
  });

  it("delivers values and keeps a bounded history", () => {
    const { sock, src } = setup(3);
    const got = vi.fn();
    src.subscribe("sub_1", got);
    sock.open();
    for (let i = 1; i <= 4; i += 1) {
      sock.deliver({ type: "value", subscriber: "sub_1", data: { value: i * 10, count: 8, start_ns: (i - 1) * 2e9, end_ns: i * 2e9 } });
    }
    sock.deliver({ type: "value", subscriber: "sub_1", data: { value: null, end_ns: 1e10 } });
    sock.deliver({ type: "value", subscriber: "other", data: { value: 1, end_ns: 1 } });
    sock.deliver({ type: "bogus" });
    sock.onmessage?.({ data: "not json" });
    expect(got).toHaveBeenCalledTimes(4);
    expect(got.mock.calls[0][0][0]).toEqual({ t: 2, value: 10, count: 8, windowS: 2 });
    expect(src.history("sub_1").map((s) => s.t)).toEqual([4, 6, 8]);
    expect(src.dropped("sub_1")).toBe(1);
  });

  it("asks for batches and reads them in order, one listener call per channel and batch", () => {
    expect(withBatch("ws://h/api/drones/d/stream")).toBe("ws://h/api/drones/d/stream?batch=1");
    expect(withBatch("ws://h/s?x=1")).toBe("ws://h/s?x=1&batch=1");
    expect(withBatch("ws://h/s?batch=0")).toBe("ws://h/s?batch=0");
    const urls: string[] = [];
    const sock = new FakeSocket();
    const src = new WebSocketSource({ url: "ws://127.0.0.1/x", connect: (u) => { urls.push(u); return sock; }, capacity: 10 });
    expect(urls).toEqual(["ws://127.0.0.1/x?batch=1"]);
    const a = vi.fn();
    const b = vi.fn();
    const link = vi.fn();
    src.subscribe("a", a);
    src.subscribe("b", b);
    src.onLinkStatus(link);
    sock.open();
    const v = (sub: string, value: number, endS: number) =>
      ({ type: "value", subscriber: sub, data: { value, start_ns: (endS - 1) * 1e9, end_ns: endS * 1e9 } });
    sock.deliver({ type: "batch", messages: [
      v("a", 1, 1), v("b", 10, 1), v("a", 2, 2), { type: "dropped", count: 3 },
      { type: "status", data: { link: "connected" } }, v("a", 3, 3), null, 7,
    ] });
    expect(a).toHaveBeenCalledTimes(1);
    expect(a.mock.calls[0][0].map((s: { value: number }) => s.value)).toEqual([1, 2, 3]);
    expect(b).toHaveBeenCalledTimes(1);
    expect(b.mock.calls[0][0].map((s: { value: number }) => s.value)).toEqual([10]);
    expect(src.history("a").map((s) => s.t)).toEqual([1, 2, 3]);
    expect(src.droppedByBackend).toBe(3);
    expect(link).toHaveBeenCalledTimes(1);
    // single messages still work, after the batch in each channel's history
    sock.deliver(v("a", 4, 4));
    expect(a).toHaveBeenCalledTimes(2);
    expect(src.history("a").map((s) => s.value)).toEqual([1, 2, 3, 4]);
    // a malformed batch is ignored
    sock.deliver({ type: "batch", messages: "nope" });
    expect(a).toHaveBeenCalledTimes(2);
  });

  it("never lets an older backfilled window replace the latest live value", () => {
    const { sock, src } = setup(20);
    const lasts: number[] = [];
    src.subscribe("sub_5", () => lasts.push(src.history("sub_5").at(-1)!.value));
    sock.open();
    const win = (k: number, value: number, backfilled?: boolean) =>
      ({ type: "value", subscriber: "sub_5", data: { value, start_ns: (k - 1) * 1e9, end_ns: k * 1e9, ...(backfilled ? { backfilled } : {}) } });
    sock.deliver(win(1, 1));
    sock.deliver(win(10, 10)); // the live LAST, after a gap 2..9
    sock.deliver({ type: "batch", messages: [win(2, 2, true), win(3, 3, true)] });
    sock.deliver(win(9, 9, true));
    sock.deliver(win(10, -10, true)); // a backfilled copy of the live window: the live one stays
    expect(lasts).toEqual([1, 10, 10, 10, 10]);
    const h = src.history("sub_5");
    expect(h.map((s) => [s.t, s.value, s.backfilled === true])).toEqual([
      [1, 1, false], [2, 2, true], [3, 3, true], [9, 9, true], [10, 10, false],
    ]);
    // a backfilled window newer than every live one is the newest (marked, for the view to say so)
    sock.deliver(win(11, 11, true));
    expect(src.history("sub_5").at(-1)).toMatchObject({ t: 11, backfilled: true });
    sock.deliver(win(11, 12)); // its live copy, late: replaces it
    expect(src.history("sub_5").at(-1)).toEqual({ t: 11, value: 12, windowS: 1 });
  });

  it("spreads ALL windows over the window and counts backend drops", () => {
    expect(toSamples({ value: [1, 2, 3, 4], start_ns: 0, end_ns: 4e9 }).map((s) => s.t)).toEqual([1, 2, 3, 4]);
    expect(toSamples({ value: true, end_ns: 1e9 })[0].value).toBe(1);
    // a value filled from the drone's archive keeps its mark; live ones carry none
    expect(toSamples({ value: 2, start_ns: 0, end_ns: 1e9, backfilled: true })[0].backfilled).toBe(true);
    expect(toSamples({ value: 2, start_ns: 0, end_ns: 1e9 })[0].backfilled).toBeUndefined();
    const { sock, src } = setup();
    sock.open();
    sock.deliver({ type: "dropped", count: 5 });
    sock.deliver({ type: "error", message: "subscriber 'x y' is not an identifier" });
    expect(src.droppedByBackend).toBe(5);
    expect(src.lastError).toMatch(/identifier/);
  });

  it("reports link status and connection state", () => {
    const { sock, src } = setup();
    const link = vi.fn();
    const states: string[] = [];
    src.onLinkStatus(link);
    src.onStateChange((s) => states.push(s));
    sock.open();
    sock.deliver({ type: "status", data: {
      link: "up", rtt_s: 0.0125, ip_bytes_in_per_s: 300, predicted_link_bytes_per_s: { drone_to_base: 296 },
      time_ns: 5e9, last_data_ns: 4.5e9,
    } });
    expect(link).toHaveBeenCalledWith({ rttMs: 12.5, measuredBytesPerS: 300, plannedBytesPerS: 296, lastFrameAgeS: 0.5, connected: true, state: "up" });
    src.close();
    expect(states).toEqual(["open", "closed"]);
  });

  it("reports a SubBroker that falls behind the link", () => {
    const { sock, src } = setup();
    const link = vi.fn();
    src.onLinkStatus(link);
    sock.open();
    sock.deliver({ type: "status", data: { link: "up", behind: true, lag_s: 2.5 } });
    expect(link).toHaveBeenLastCalledWith(expect.objectContaining({ behind: true, lagS: 2.5 }));
    sock.deliver({ type: "status", data: { link: "up", behind: false, lag_s: 0.01 } });
    expect(link).toHaveBeenLastCalledWith(expect.objectContaining({ behind: false, lagS: 0.01 }));
    src.close();
  });
});

describe("the contracts' vectors (contracts/vectors)", () => {
  it("turns every delivered value the SubBroker writes into the samples a chart plots", () => {
    for (const c of deliveredVectors.vectors) {
      const d = JSON.parse(c.line) as DeliveredValue;
      const got = toSamples(d).map((s) => [s.t, s.value]);
      expect(got.length, c.name).toBe(c.samples.length);
      got.forEach(([t, v], i) => {
        expect(t, c.name).toBeCloseTo(c.samples[i][0], 6);
        expect(v, c.name).toBe(c.samples[i][1]);
      });
    }
  });

  it("reads the status document's fields as the SubBroker sends them", () => {
    for (const c of statusVectors.vectors) {
      const got = toLinkStatus(c.document as SubBrokerStatus);
      const want = c.link_status;
      expect(got.connected, c.name).toBe(want.connected);
      expect(got.state, c.name).toBe(want.state);
      expect(got.measuredBytesPerS, c.name).toBe(want.measuredBytesPerS);
      expect(got.plannedBytesPerS, c.name).toBe(want.plannedBytesPerS);
      expect(got.behind, c.name).toBe(want.behind);
      expect(got.lagS, c.name).toBe(want.lagS);
      expect(got.sensors ?? null, c.name).toEqual("sensors" in want ? want.sensors : null);
      if (want.rttMs === null) expect(got.rttMs).toBeNull();
      else expect(got.rttMs, c.name).toBeCloseTo(want.rttMs, 9);
      if (want.lastFrameAgeS === null) expect(got.lastFrameAgeS).toBeNull();
      else expect(got.lastFrameAgeS, c.name).toBeCloseTo(want.lastFrameAgeS, 3);
    }
  });
});

describe("toLinkStatus", () => {
  it("carries the archive space the PubBroker reports", async () => {
    const { toLinkStatus } = await import("./WebSocketSource");
    const s = toLinkStatus({ link: "up", pubbroker: { disk_free_mb: 100, archive_rate_bps: 1e5, archive_state: 1 } });
    expect(s.archive?.state).toBe("low");
    expect(s.archive?.warn).toBe(true);
    expect(s.archive?.hoursLeft).toBeCloseTo((100 * 1048576) / 1e5 / 3600, 6);
  });
});

describe("toLinkStatus over a datagram link", () => {
  it("takes the measured and planned bytes/s of the declared transport and the radio's figures", () => {
    const s = toLinkStatus({
      link: "up", rtt_s: 0.08, ip_bytes_in_per_s: 300, time_ns: 2e9, last_data_ns: 1e9,
      predicted_link_bytes_per_s: { drone_to_base: 292.5 } as SubBrokerStatus["predicted_link_bytes_per_s"],
      link_budget: { drone_to_base: 100.8, base_to_drone: 1.4 },
      radio: { transport: "udp", wire_bytes_in_per_s: 98.2, wire_bytes_out_per_s: 2.1, loss: 0.05,
               retransmissions: 7, forged: 2, replayed: 1, malformed: 0 } as SubBrokerStatus["radio"],
    });
    expect(s.measuredBytesPerS).toBe(98.2);
    expect(s.plannedBytesPerS).toBe(100.8);
    expect(s.radio).toEqual({ transport: "udp", loss: 0.05, retransmissions: 7, forged: 2, replayed: 1,
                              malformed: 0, outBytesPerS: 2.1, plannedOutBytesPerS: 1.4 });
    expect(toLinkStatus({ link: "up", ip_bytes_in_per_s: 300 }).radio).toBeUndefined();
  });
});

describe("live QARTOD flags", () => {
  it("reads the backend's [[end_ns, flag], ...], nothing from a malformed one", () => {
    expect(qcFlags("s", [[2e9, 4], [4e9, 1]])).toEqual([{ channel: "s", t: 2, qc: 4 }, { channel: "s", t: 4, qc: 1 }]);
    expect(qcFlags("s", "bad")).toEqual([]);
    expect(qcFlags("s", [[1, "x"], [1], null])).toEqual([]);
  });

  it("marks the window a later value flags (a spike is known one window late), in batches too", () => {
    const sock = new FakeSocket();
    const src = new WebSocketSource({ url: "ws://127.0.0.1/x", connect: () => sock, capacity: 10 });
    src.subscribe("sub_t", () => undefined);
    const value = (i: number, v: number, qc: number[][]) =>
      ({ type: "value", subscriber: "sub_t", data: { value: v, start_ns: (i - 1) * 2e9, end_ns: i * 2e9 }, qc });
    sock.deliver(value(1, 10, [[2e9, 2]]));
    sock.deliver(value(2, 10, [[2e9, 2], [4e9, 1]]));
    sock.deliver(value(3, 30, [[4e9, 1], [6e9, 1]]));
    sock.deliver({ type: "batch", messages: [value(4, 10, [[6e9, 4], [8e9, 1]])] });
    expect(src.history("sub_t").map((s) => s.qc)).toEqual([2, 1, 4, 1]);
    const channels = [{ samples: src.history("sub_t"), periodS: 2 }];
    expect(flaggedSeries(channels, [2, 4, 6, 8])).toEqual([[undefined, undefined, 30, undefined]]);
    expect(qcSummary(channels)).toBe("1 flagged (QARTOD: 0 suspect, 1 bad)");
    expect(qcSummary([{ samples: [{ t: 1, value: 1, qc: 1 }] }])).toBe("");
  });
});
