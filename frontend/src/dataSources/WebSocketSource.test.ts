import { describe, expect, it, vi } from "vitest";
import { WebSocketSource, type SocketLike } from "./WebSocketSource";
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

  it("delivers batches and keeps a bounded history", () => {
    const { sock, src } = setup(3);
    const got = vi.fn();
    src.subscribe("sub_1", got);
    sock.open();
    sock.deliver({ type: "values", subscriber: "sub_1", values: [1, 2, 3, 4].map((i) => ({ t: i, value: i * 10, count: 8 })) });
    sock.deliver({ type: "value", subscriber: "sub_1", t: 5, value: 50 });
    sock.deliver({ type: "values", subscriber: "other", values: [{ t: 1, value: 1 }] });
    sock.deliver({ type: "bogus" });
    sock.onmessage?.({ data: "not json" });
    expect(got).toHaveBeenCalledTimes(2);
    expect(got.mock.calls[0][0][0]).toEqual({ t: 1, value: 10, count: 8 });
    expect(src.history("sub_1").map((s) => s.t)).toEqual([3, 4, 5]);
    expect(src.dropped("sub_1")).toBe(2);
  });

  it("reports link status and connection state", () => {
    const { sock, src } = setup();
    const link = vi.fn();
    const states: string[] = [];
    src.onLinkStatus(link);
    src.onStateChange((s) => states.push(s));
    sock.open();
    sock.deliver({ type: "link", rtt_ms: 12.5, measured_bytes_per_s: 300, planned_bytes_per_s: 296, connected: true });
    expect(link).toHaveBeenCalledWith({ rttMs: 12.5, measuredBytesPerS: 300, plannedBytesPerS: 296, lastFrameAgeS: null, connected: true });
    src.close();
    expect(states).toEqual(["open", "closed"]);
  });
});
