/**
 * DataSource over the backend's stream WebSocket, /api/drones/<drone>/stream
 * (backend/src/modd_backend/routers/live.py): one socket per browser tab
 * and drone, multiplexing subscriptions.
 *
 * Wire messages (JSON text frames):
 *   → {"op": "subscribe"|"unsubscribe", "subscriber": NAME}
 *   ← {"type": "value", "subscriber": NAME, "data": DeliveredValue}
 *   ← {"type": "status", "data": SubBrokerStatus}
 *        Both are contracts (metamodel/src/modd_contracts/schemas, types generated in
 *        core/contracts.gen.ts): the functions below read their fields by those types,
 *        each as possibly absent, since the socket is not trusted.
 *   → {"op": "watch", "project": ID}   ← {"type": "saved", "project", "revision", "author", "message"}
 *   ← {"type": "dropped", "count": n}   the backend dropped n messages for a slow page
 *   ← {"type": "batch", "messages": [m, …]}  several of the above in one frame, in order
 *        (the socket asks for them with ?batch=1: one frame per wake-up of the backend's
 *        sender instead of one per value; each channel's listeners get one call per batch)
 *   ← {"type": "error", "message": …}; subscribed, unsubscribed, pong: ignored
 * The socket factory is injected (tests pass a fake).
 */
import type { DeliveredValue, SubBrokerStatus } from "../core/contracts.gen";
import { RingBuffer } from "./RingBuffer";
import { archiveSpace } from "../core/archiveSpace";
import { instrumentsHealth } from "../core/instrumentHealth";
import { onboardLines } from "../core/onboard";
import type { ChannelListener, ConnectionState, DataSource, LinkStatus, Sample, SavedEvent, SupervisorStop } from "./types";

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

/** Samples of one delivered window; a list (ALL) gives one sample per raw value. Empty windows give none. */
export function toSamples(d: Partial<DeliveredValue>): Sample[] {
  const endNs = num(d.end_ns);
  const startNs = num(d.start_ns);
  if (endNs === null) return [];
  const t = endNs / 1e9;
  const windowS = startNs !== null ? (endNs - startNs) / 1e9 : undefined;
  const count = typeof d.count === "number" ? d.count : undefined;
  const one = (value: unknown, at: number): Sample | null => {
    const v = Number(value);
    if (value === null || value === undefined || !Number.isFinite(v)) return null;
    const s: Sample = { t: at, value: v };
    if (windowS !== undefined) s.windowS = windowS;
    if (count !== undefined) s.count = count;
    if (d.backfilled === true) s.backfilled = true;
    return s;
  };
  if (Array.isArray(d.value) && Array.isArray(d.event_ns) && d.event_ns.length === d.value.length) {
    // An event window: each event at its own sample time (docs/subbroker.md, "Delivered values").
    const delivered = num(d.delivered_ns);
    const times = d.event_ns;
    return d.value.map((v, i) => {
      const s = one(v, Number(times[i]) / 1e9);
      if (s) { s.event = true; if (delivered !== null) s.deliveredNs = delivered; }
      return s;
    }).filter((s): s is Sample => s !== null && Number.isFinite(s.t));
  }
  if (Array.isArray(d.value)) {
    const n = d.value.length;
    const w = windowS ?? 0;
    return d.value.map((v, i) => one(v, t - w + (w * (i + 1)) / n)).filter((s): s is Sample => s !== null);
  }
  const s = one(d.value, t);
  return s ? [s] : [];
}

/** The stream URL asking the backend for batched frames (``batch=1``). */
export function withBatch(url: string): string {
  if (/[?&]batch=/.test(url)) return url;
  return url + (url.includes("?") ? "&" : "?") + "batch=1";
}

/** Two samples of the same window (same time and window length): a backfill repeating a live value. */
/** A window's QARTOD flag, as the backend sends it beside a value (`qc: [[end_ns, flag], ...]`). */
interface QcFlag { channel: string; t: number; qc: number }

/** The flags of a value message (none when absent or malformed). */
export function qcFlags(channel: string, raw: unknown): QcFlag[] {
  if (!Array.isArray(raw)) return [];
  return raw.slice(0, 4).flatMap((p): QcFlag[] => {
    if (!Array.isArray(p) || p.length !== 2) return [];
    const [endNs, qc] = p.map(Number);
    return Number.isFinite(endNs) && Number.isInteger(qc) ? [{ channel, t: endNs / 1e9, qc }] : [];
  });
}

function sameWindow(a: Sample, b: Sample): boolean {
  return a.t === b.t && a.windowS === b.windowS;
}

function num(x: unknown): number | null {
  return x === null || x === undefined || !Number.isFinite(Number(x)) ? null : Number(x);
}

/** Printable, bounded text from a status field (a process's reason may quote its log). */
function text(x: unknown, max = 300): string {
  // eslint-disable-next-line no-control-regex
  const s = String(x ?? "").replace(/[\u0000-\u001f\u007f-\u009f]+/g, " ").trim();
  return s.length > max ? `${s.slice(0, max - 1)}…` : s;
}

/** The `supervisor` field `modd up` puts when it gave up the run, as `{ gaveUp }`; null otherwise. */
export function supervisorStop(x: unknown): { gaveUp: SupervisorStop } | null {
  if (!x || typeof x !== "object") return null;
  const s = x as Record<string, unknown>;
  if (s.state !== "GAVE_UP") return null;
  const code = num(s.exit_code);
  return { gaveUp: { process: text(s.process, 80) || "a process", exitCode: code, reason: text(s.reason), log: text(s.log) } };
}

/** LinkStatus from the SubBroker's status document; the link is connected when its state is "up". */
export function toLinkStatus(d: Partial<SubBrokerStatus>): LinkStatus {
  // over udp/serial the plan of the declared transport, else the TCP prediction
  const predicted = (d.link_budget ?? d.predicted_link_bytes_per_s) as Record<string, unknown> | null | undefined;
  const radio = d.radio as Record<string, unknown> | null | undefined;
  const rtt = num(d.rtt_s);
  const last = num(d.last_data_ns);
  const now = num(d.time_ns);
  const archive = archiveSpace(d.pubbroker as Record<string, unknown> | undefined);
  return {
    rttMs: rtt === null ? null : rtt * 1000,
    measuredBytesPerS: num(radio ? radio.wire_bytes_in_per_s : d.ip_bytes_in_per_s),
    plannedBytesPerS: predicted ? num(predicted.drone_to_base) : null,
    lastFrameAgeS: last !== null && now !== null ? (now - last) / 1e9 : null,
    connected: d.link === "up",
    state: typeof d.link === "string" ? d.link : undefined,
    ...(typeof d.behind === "boolean" ? { behind: d.behind, lagS: num(d.lag_s) } : {}),
    ...(archive ? { archive } : {}),
    ...(d.sensors ? { sensors: instrumentsHealth(d.sensors) } : {}),
    ...(d.onboard ? { onboard: onboardLines(d.onboard, true) } : {}),
    ...(supervisorStop(d.supervisor) ?? {}),
    ...(radio ? {
      radio: {
        transport: String(radio.transport ?? ""),
        loss: num(radio.loss),
        retransmissions: num(radio.retransmissions) ?? 0,
        forged: num(radio.forged) ?? 0,
        replayed: num(radio.replayed) ?? 0,
        malformed: num(radio.malformed) ?? 0,
        outBytesPerS: num(radio.wire_bytes_out_per_s),
        plannedOutBytesPerS: predicted ? num(predicted.base_to_drone) : null,
      },
    } : {}),
  };
}

export class WebSocketSource implements DataSource {
  state: ConnectionState = "connecting";
  private readonly socket: SocketLike;
  private readonly listeners = new Map<string, Set<ChannelListener>>();
  private readonly buffers = new Map<string, RingBuffer<Sample>>();
  private readonly linkListeners = new Set<(s: LinkStatus) => void>();
  private readonly stateListeners = new Set<(s: ConnectionState) => void>();
  private readonly capacity: number;
  private readonly savedListeners = new Map<number, Set<(e: SavedEvent) => void>>();

  constructor(opts: WebSocketSourceOptions) {
    this.capacity = opts.capacity ?? 2000;
    this.socket = opts.connect(withBatch(opts.url));
    this.socket.onopen = () => {
      this.setState("open");
      for (const channel of this.listeners.keys()) this.send({ op: "subscribe", subscriber: channel });
      for (const project of this.savedListeners.keys()) this.send({ op: "watch", project });
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
    const samples = new Map<string, Sample[]>(); // per channel, in arrival order
    const flags: QcFlag[] = [];
    if (msg.type === "batch" && Array.isArray(msg.messages)) {
      for (const m of msg.messages) {
        if (m && typeof m === "object") this.handle(m as Raw, samples, flags);
      }
    } else {
      this.handle(msg, samples, flags);
    }
    samples.forEach((batch, channel) => {
      const b = this.buffer(channel);
      // Live values come in time order; a backfilled one goes in place among them, so
      // the newest (the "last" a view shows) stays the newest whatever arrives late. A
      // window already held is replaced, never doubled, except a live one by its
      // backfilled copy: the live value stays (a historical one never hides it).
      batch.forEach((s) => {
        if (s.backfilled && b.findLast((x) => !x.backfilled && sameWindow(x, s))) return;
        b.insertOrdered(s, (x) => x.t, sameWindow);
      });
    });
    for (const f of flags) this.flag(f);
    samples.forEach((batch, channel) => this.listeners.get(channel)?.forEach((l) => l(batch)));
  }

  /** Sets a window's QARTOD flag (the newest windows: a flag revises this one or the one before). */
  private flag({ channel, t, qc }: QcFlag): void {
    const s = this.buffers.get(channel)?.findLast((x) => x.t === t && !x.backfilled, 8);
    if (s) s.qc = qc;
  }

  private handle(msg: Raw, samples: Map<string, Sample[]>, flags: QcFlag[]): void {
    if (msg.type === "value") {
      const channel = String(msg.subscriber ?? "");
      const batch = toSamples((msg.data ?? {}) as Partial<DeliveredValue>);
      if (!channel || batch.length === 0) return;
      flags.push(...qcFlags(channel, msg.qc));
      const list = samples.get(channel);
      if (list) list.push(...batch);
      else samples.set(channel, batch);
    } else if (msg.type === "status") {
      const status = toLinkStatus((msg.data ?? {}) as Partial<SubBrokerStatus>);
      this.linkListeners.forEach((l) => l(status));
    } else if (msg.type === "saved") {
      const e: SavedEvent = { project: Number(msg.project), revision: Number(msg.revision), author: String(msg.author ?? ""), message: String(msg.message ?? "") };
      this.savedListeners.get(e.project)?.forEach((l) => l(e));
    } else if (msg.type === "dropped") {
      this.droppedByBackend += Number(msg.count) || 0;
    } else if (msg.type === "error") {
      this.lastError = String(msg.message ?? "error");
    }
  }

  /** Messages the backend dropped because this page was slow. */
  droppedByBackend = 0;
  lastError: string | null = null;

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

  watchProject(project: number, listener: (e: SavedEvent) => void): () => void {
    let set = this.savedListeners.get(project);
    if (!set) {
      set = new Set();
      this.savedListeners.set(project, set);
      this.send({ op: "watch", project });
    }
    set.add(listener);
    return () => {
      const s = this.savedListeners.get(project);
      if (!s) return;
      s.delete(listener);
      if (s.size === 0) {
        this.savedListeners.delete(project);
        this.send({ op: "unwatch", project });
      }
    };
  }

  onStateChange(listener: (s: ConnectionState) => void): () => void {
    this.stateListeners.add(listener);
    return () => this.stateListeners.delete(listener);
  }

  close(): void {
    this.socket.close();
  }
}
