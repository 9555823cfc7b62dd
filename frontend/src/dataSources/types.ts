import type { ArchiveSpace } from "../core/archiveSpace";
import type { InstrumentHealth } from "../core/instrumentHealth";
import type { OnboardLine } from "../core/onboard";
/**
 * Live data behind one interface. Panels never open sockets: they get a
 * `DataSource` from the services context and subscribe to channels.
 *
 * Contract:
 * - `subscribe(channel, listener)` starts the channel on the source's first
 *   listener and stops it after the last one leaves (the returned function).
 * - Listeners are called with batches, in arrival order, on the main thread.
 * - Backpressure: a source never queues without bound. Values are kept in a
 *   ring buffer per channel (`history`, at most `capacity` points); when the
 *   page falls behind the oldest points are dropped, and `dropped` counts them.
 *   The backend does the same on its side (a slow browser loses its oldest values).
 */

/** One delivered value of a subscription. */
export interface Sample {
  /** Time of the value, seconds since the Unix epoch. */
  t: number;
  value: number;
  /** Aggregation window it covers, seconds (optional). */
  windowS?: number;
  /** Number of raw samples aggregated (optional). */
  count?: number;
  /** Recomputed from the drone's archive after the link missed it (backfill). */
  backfilled?: boolean;
  /** An event of an ON_CHANGE or THRESHOLD window: `t` is its sample time (the value's `event_ns`). */
  event?: boolean;
  /** When the SubBroker delivered the window (its `delivered_ns`), ns since the epoch; for events. */
  deliveredNs?: number;
  /** The window's QARTOD aggregate flag from the backend (1 pass, 2 not evaluated, 3 suspect, 4 fail). */
  qc?: number;
}

/** Link status of a drone: measured against planned. */
export interface LinkStatus {
  rttMs: number | null;
  measuredBytesPerS: number | null;
  plannedBytesPerS: number | null;
  /** Seconds since the last frame from the drone. */
  lastFrameAgeS: number | null;
  connected: boolean;
  /** The SubBroker's word for the link state, as sent. */
  state?: string;
  /** The SubBroker falls behind the link (its status' `behind`), when it says. */
  behind?: boolean;
  /** How much later than its best the SubBroker delivers (status' `lag_s`). */
  lagS?: number | null;
  /** The on-board archive's space (core/archiveSpace.ts), once the PubBroker reported it. */
  archive?: ArchiveSpace | null;
  /** Over udp or serial (status' `radio`): what the datagram link measures. */
  radio?: RadioFigures;
  /** The plug-and-play instruments' health (status' `sensors`), when the drone reports it. */
  sensors?: InstrumentHealth[];
  /** what the on-board processes did with the last deploy (core/onboard.ts) */
  onboard?: OnboardLine[];
  /** The supervisor (`modd up`) gave up the run (status' `supervisor`): which process, why. */
  gaveUp?: SupervisorStop;
}

/** Why `modd up` stopped the run (docs/reliability.md, "Base station, store and tools"). */
export interface SupervisorStop {
  process: string;
  exitCode: number | null;
  reason: string;
  /** The process's log file, on the base station. */
  log: string;
}

/** A datagram link's figures (docs/subbroker.md, "Status": `radio`). */
export interface RadioFigures {
  transport: string;
  /** Share of the slots that did not arrive the first time (0..1). */
  loss: number | null;
  retransmissions: number;
  forged: number;
  replayed: number;
  malformed: number;
  /** Measured bytes/s on the wire, base to drone, and the plan's. */
  outBytesPerS: number | null;
  plannedOutBytesPerS: number | null;
}

export type ConnectionState = "connecting" | "open" | "closed" | "error";

export interface ChannelListener {
  (batch: readonly Sample[]): void;
}

export interface DataSource {
  readonly state: ConnectionState;
  subscribe(channel: string, listener: ChannelListener): () => void;
  /** Everything kept for a channel, oldest first. */
  history(channel: string): readonly Sample[];
  /** Points dropped for a channel because the buffer was full. */
  dropped(channel: string): number;
  onLinkStatus(listener: (s: LinkStatus) => void): () => void;
  onStateChange(listener: (s: ConnectionState) => void): () => void;
  /** Saves of a project, as the backend announces them (optional: sources without a backend have none). */
  watchProject?(project: number, listener: (e: SavedEvent) => void): () => void;
  close(): void;
}

/** A revision someone saved (stream message `{"type": "saved"}`). */
export interface SavedEvent {
  project: number;
  revision: number;
  author: string;
  message: string;
}
