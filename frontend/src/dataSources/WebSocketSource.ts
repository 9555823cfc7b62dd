/**
 * DataSource over the backend's stream WebSocket (one socket per browser tab
 * and drone, multiplexing subscriptions).
 *
 * Wire messages (JSON text frames):
 *   → {"op": "subscribe", "subscriber": NAME}   → {"op": "unsubscribe", "subscriber": NAME}
 *   ← {"type": "values", "subscriber": NAME, "values": [{"t": s, "value": x, "window_s"?, "count"?}]}
 *   ← {"type": "value", "subscriber": NAME, "t": s, "value": x}           (single value)
 *   ← {"type": "link", "rtt_ms", "measured_bytes_per_s", "planned_bytes_per_s", "last_frame_age_s", "connected"}
 * Unknown message types are ignored, so the backend can add some.
 * The socket factory is injected (tests pass a fake).
 */
import { RingBuffer } from "./RingBuffer";
import type { ChannelListener, ConnectionState, DataSource, LinkStatus, Sample } from "./types";

export interface SocketLike {
  readyState: number;
  send(data: string): void;
  close(): void;
  onopen: ((ev: unknown) => void) | null;
  onmessage: ((ev: { data: unknown }) => void) | null;
  onclose: ((ev: unknown) => void) | null;
  onerror: ((ev: unknown) => void) | null;
}

export interface WebSocketSourceOptions {
  url: string;
  connect: (url: string) => SocketLike;
  /** Points kept per channel. */
  capacity?: number;
}

const OPEN = 1;

type Raw = Record<string, unknown>;

function toSample(v: Raw): Sample | null {
  const t = Number(v.t);
  const value = Number(v.value);
  if (!Number.isFinite(t) || !Number.isFinite(value)) return null;
  const s: Sample = { t, value };
  if (v.window_s !== undefined) s.windowS = Number(v.window_s);
  if (v.count !== undefined) s.count = Number(v.count);
  return s;
}

export class WebSocketSource implements DataSource {
  state: ConnectionState = "connecting";
  private readonly socket: SocketLike;
  private readonly listeners = new Map<string, Set<ChannelListener>>();
  private readonly buffers = new Map<string, RingBuffer<Sample>>();
  private readonly linkListeners = new Set<(s: LinkStatus) => void>();
  private readonly stateListeners = new Set<(s: ConnectionState) => void>();
  private readonly capacity: number;

  constructor(opts: WebSocketSourceOptions) {
    this.capacity = opts.capacity ?? 2000;
    this.socket = opts.connect(opts.url);
    this.socket.onopen = () => {
      this.setState("open");
      for (const channel of this.listeners.keys()) this.send({ op: "subscribe", subscriber: channel });
    };
    this.socket.onclose = () => this.setState("closed");
    this.socket.onerror = () => this.setState("error");
    this.socket.onmessage = (ev) => this.receive(ev.data);
  }

  private setState(s: ConnectionState): void {
    this.state = s;
    this.stateListeners.forEach((l) => l(s));
  }

  private send(msg: object): void {
    if (this.socket.readyState === OPEN) this.socket.send(JSON.stringify(msg));
  }

  private buffer(channel: string): RingBuffer<Sample> {
    let b = this.buffers.get(channel);
    if (!b) {
      b = new RingBuffer<Sample>(this.capacity);
      this.buffers.set(channel, b);
    }
    return b;
  }

  private receive(data: unknown): void {
    let msg: Raw;
    try {
      msg = JSON.parse(String(data)) as Raw;
    } catch {
      return;
    }
    if (msg.type === "values" || msg.type === "value") {
      const channel = String(msg.subscriber ?? "");
      const raw = msg.type === "values" ? (msg.values as Raw[] | undefined) ?? [] : [msg];
      const batch = raw.map(toSample).filter((s): s is Sample => s !== null);
      if (!channel || batch.length === 0) return;
      const b = this.buffer(channel);
      batch.forEach((s) => b.push(s));
      this.listeners.get(channel)?.forEach((l) => l(batch));
    } else if (msg.type === "link") {
      const num = (x: unknown) => (x === null || x === undefined ? null : Number(x));
      const status: LinkStatus = {
        rttMs: num(msg.rtt_ms),
        measuredBytesPerS: num(msg.measured_bytes_per_s),
        plannedBytesPerS: num(msg.planned_bytes_per_s),
        lastFrameAgeS: num(msg.last_frame_age_s),
        connected: Boolean(msg.connected),
      };
      this.linkListeners.forEach((l) => l(status));
    }
  }

  subscribe(channel: string, listener: ChannelListener): () => void {
    let set = this.listeners.get(channel);
    if (!set) {
      set = new Set();
      this.listeners.set(channel, set);
      this.send({ op: "subscribe", subscriber: channel });
    }
    set.add(listener);
    return () => {
      const s = this.listeners.get(channel);
      if (!s) return;
      s.delete(listener);
      if (s.size === 0) {
        this.listeners.delete(channel);
        this.send({ op: "unsubscribe", subscriber: channel });
      }
    };
  }

  history(channel: string): readonly Sample[] {
    return this.buffers.get(channel)?.toArray() ?? [];
  }

  dropped(channel: string): number {
    return this.buffers.get(channel)?.dropped ?? 0;
  }

  onLinkStatus(listener: (s: LinkStatus) => void): () => void {
    this.linkListeners.add(listener);
    return () => this.linkListeners.delete(listener);
  }

  onStateChange(listener: (s: ConnectionState) => void): () => void {
    this.stateListeners.add(listener);
    return () => this.stateListeners.delete(listener);
  }

  close(): void {
    this.socket.close();
  }
}
