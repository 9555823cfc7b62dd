/**
 * A live view never shows a historical value as the latest: the backend's
 * browser-facing stream (the live relay's messages, in arrival order) fed to
 * the WebSocketSource, the newest sample checked after every message against
 * the stream itself (the newest live window's end so far).
 *
 * With MODD_RELAY_CAPTURE (a JSON file `{ subscriber, messages }`) the
 * messages are a real run's: tests/subbroker/test_backfill_historical.py
 * captures them from a PubBroker and a SubBroker through a cut link and a
 * backfill. Without it, a stream of the same shape: live windows, an outage,
 * the link back, then the outage's windows backfilled among live ones.
 */
import { readFileSync } from "node:fs";
import { describe, expect, it } from "vitest";
import { WebSocketSource, type SocketLike } from "./WebSocketSource";

type Message = { type: string; subscriber: string; data: { end_ns: number; start_ns: number; value: unknown; backfilled?: boolean } };

function stream(): { subscriber: string; messages: Message[] } {
  const path = process.env.MODD_RELAY_CAPTURE;
  if (path) return JSON.parse(readFileSync(path, "utf-8"));
  const win = (k: number, backfilled = false): Message => ({
    type: "value", subscriber: "sub_7",
    data: { start_ns: (k - 1) * 25e7, end_ns: k * 25e7, value: k, ...(backfilled ? { backfilled } : {}) },
  });
  const live = [1, 2, 3, 4, 20, 21, 22].map((k) => win(k));
  const filled = [5, 6, 7, 8, 9, 10].map((k) => win(k, true));
  // the link is back (20, 21), the backfill arrives among live windows (22)
  return { subscriber: "sub_7", messages: [...live.slice(0, 6), ...filled.slice(0, 3), live[6], ...filled.slice(3)] };
}

describe("historical values in the live view", () => {
  it("never shows a backfilled window as the latest while a newer live one is held", () => {
    const { subscriber, messages } = stream();
    let sock: SocketLike & { onmessage: SocketLike["onmessage"] } = null!;
    const src = new WebSocketSource({
      url: "ws://127.0.0.1/x", capacity: 1_000_000,
      connect: () => (sock = { readyState: 1, send: () => {}, close: () => {}, onopen: null, onmessage: null, onclose: null, onerror: null }),
    });
    src.subscribe(subscriber, () => {});
    let newestLive = -Infinity;
    let historicalBehindLive = 0;
    for (const m of messages) {
      const end = m.data.end_ns / 1e9;
      if (m.data.backfilled === true && end < newestLive) historicalBehindLive += 1;
      const drawn = m.data.value !== null && m.data.value !== undefined; // an empty window draws nothing
      if (m.data.backfilled !== true && drawn) newestLive = Math.max(newestLive, end);
      sock.onmessage?.({ data: JSON.stringify(m) });
      const last = src.history(subscriber).at(-1);
      if (!last) {
        expect(newestLive).toBe(-Infinity);
        continue;
      }
      // the latest is the newest live window, or a marked one newer than every live one
      expect(last.t).toBeGreaterThanOrEqual(newestLive);
      if (last.backfilled) expect(last.t).toBeGreaterThan(newestLive);
    }
    // the run had backfilled windows arriving after newer live ones (the case under test)
    expect(historicalBehindLive).toBeGreaterThan(0);
    // and each is in the history, marked, in its place in time
    const h = src.history(subscriber);
    const marked = h.filter((s) => s.backfilled).map((s) => s.t);
    const sent = messages.filter((m) => m.data.backfilled === true).map((m) => m.data.end_ns / 1e9);
    expect(marked).toEqual([...new Set(sent)].filter((t) => !h.some((s) => s.t === t && !s.backfilled)).sort((a, b) => a - b));
    expect(h.map((s) => s.t)).toEqual([...h.map((s) => s.t)].sort((a, b) => a - b));
  });
});
