/**
 * DataSource over archived series (read from the drone's MCAP archive by the
 * backend), played back on a cursor: the charts that show live values show
 * an archive the same way. `history(channel)` is what was recorded up to the
 * cursor; `seek` moves it, `play` advances it at `rate` × real time until
 * the end, `pause` stops. Listeners get each newly revealed batch; after a
 * seek they get an empty batch and re-read `history`.
 *
 * @example
 *   const p = new PlaybackSource({ "usv.gps.latitude": samples });
 *   p.seek(p.start + 10); p.play(10); ... p.pause();
 */
import type { ChannelListener, ConnectionState, DataSource, Sample } from "./types";

export class PlaybackSource implements DataSource {
  readonly state: ConnectionState = "open";
  readonly start: number;
  readonly end: number;
  private cursorT: number;
  /** How many samples of each channel are at or before the cursor. */
  private shown = new Map<string, number>();
  private readonly listeners = new Map<string, Set<ChannelListener>>();
  private readonly cursorListeners = new Set<(t: number, playing: boolean) => void>();
  private timer: ReturnType<typeof setInterval> | null = null;
  rate = 1;

  constructor(private readonly series: Record<string, readonly Sample[]>, private readonly tickMs = 100) {
    const ts = Object.values(series).flatMap((s) => (s.length ? [s[0].t, s[s.length - 1].t] : []));
    this.start = ts.length ? Math.min(...ts) : 0;
    this.end = ts.length ? Math.max(...ts) : 0;
    this.cursorT = this.start;
    this.seek(this.start);
  }

  get cursor(): number { return this.cursorT; }
  get playing(): boolean { return this.timer !== null; }

  /** Index of the first sample after `t`. */
  private count(s: readonly Sample[], t: number): number {
    let lo = 0, hi = s.length;
    while (lo < hi) { const mid = (lo + hi) >> 1; if (s[mid].t <= t) lo = mid + 1; else hi = mid; }
    return lo;
  }

  seek(t: number): void {
    this.cursorT = Math.min(Math.max(t, this.start), this.end);
    for (const [channel, s] of Object.entries(this.series)) this.shown.set(channel, this.count(s, this.cursorT));
    this.listeners.forEach((set) => set.forEach((l) => l([])));
    this.emitCursor();
  }

  /** Advances the cursor by `dt` seconds of recorded time, revealing what it passes. */
  advance(dt: number): void {
    this.cursorT = Math.min(this.cursorT + dt, this.end);
    for (const [channel, s] of Object.entries(this.series)) {
      const from = this.shown.get(channel) ?? 0;
      const to = this.count(s, this.cursorT);
      this.shown.set(channel, to);
      if (to > from) this.listeners.get(channel)?.forEach((l) => l(s.slice(from, to)));
    }
    if (this.cursorT >= this.end) this.pause();
    else this.emitCursor();
  }

  play(rate = this.rate): void {
    this.rate = rate;
    if (this.timer) return;
    if (this.cursorT >= this.end) this.seek(this.start);
    this.timer = setInterval(() => this.advance((this.tickMs / 1000) * this.rate), this.tickMs);
    this.emitCursor();
  }

  pause(): void {
    if (this.timer) clearInterval(this.timer);
    this.timer = null;
    this.emitCursor();
  }

  onCursor(listener: (t: number, playing: boolean) => void): () => void {
    this.cursorListeners.add(listener);
    return () => this.cursorListeners.delete(listener);
  }

  private emitCursor(): void {
    this.cursorListeners.forEach((l) => l(this.cursorT, this.playing));
  }

  subscribe(channel: string, listener: ChannelListener): () => void {
    let set = this.listeners.get(channel);
    if (!set) { set = new Set(); this.listeners.set(channel, set); }
    set.add(listener);
    return () => set.delete(listener);
  }

  history(channel: string): readonly Sample[] {
    return (this.series[channel] ?? []).slice(0, this.shown.get(channel) ?? 0);
  }

  dropped(): number { return 0; }
  onLinkStatus(): () => void { return () => undefined; }
  onStateChange(): () => void { return () => undefined; }
  close(): void { this.pause(); }
}

/** Samples from an archive series' [log time ns, value] points (numbers and booleans only). */
export function archiveSamples(points: ReadonlyArray<[number, unknown]>): Sample[] {
  return points
    .filter(([, v]) => typeof v === "number" || typeof v === "boolean")
    .map(([t, v]) => ({ t: t / 1e9, value: Number(v) }))
    .sort((a, b) => a.t - b.t);
}


