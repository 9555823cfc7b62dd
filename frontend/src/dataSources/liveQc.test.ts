import { describe, expect, it } from "vitest";
import { WebSocketSource, qcFlags, type SocketLike } from "./WebSocketSource";
import { flaggedSeries, qcSummary } from "../core/chartData";

class FakeSocket implements SocketLike {
  readyState = 0;
  onopen: SocketLike["onopen"] = null;
  onmessage: SocketLike["onmessage"] = null;
  onclose: SocketLike["onclose"] = null;
  onerror: SocketLike["onerror"] = null;
  send() { /* subscriptions are not looked at here */ }
  close() { this.readyState = 3; }
  deliver(msg: object) { this.onmessage?.({ data: JSON.stringify(msg) }); }
}

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
