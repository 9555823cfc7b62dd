/**
 * Is the drone's link lost, and since when? From the stream's connection
 * state and the SubBroker's last status (sent every second), judged on the
 * browser's clock, the way a ground station shows "communication lost".
 *
 * Nothing is judged before the first status (no drone yet: no alarm).
 * Lost when: the stream to the workbench is closed; no status came for
 * `statusTimeoutS`; the SubBroker says the link is not up; or no frame came
 * from the drone for `staleS` (the frame age grows on our clock between
 * statuses).
 *
 * @example
 *   linkHealth({ stream: "open", status, statusAt: 100, now: 112 })
 *   // { down: true, reason: "no status from the base station for 12 s", lastFrameAt: 95 }
 */
import type { ConnectionState, LinkStatus, SupervisorStop } from "../dataSources/types";

export interface LinkHealthInput {
  stream: ConnectionState;
  status: LinkStatus | null;
  /** When `status` arrived, seconds on the browser's clock. */
  statusAt: number | null;
  now: number;
  /** No frame for this long is a loss (default 5 s; give ≥ 2 slot gaps of the plan). */
  staleS?: number;
  statusTimeoutS?: number;
}

export interface LinkHealth {
  down: boolean;
  /** Why, in words (null while up or unknown). */
  reason: string | null;
  /** When the last frame from the drone arrived, seconds on the browser's clock (null: unknown). */
  lastFrameAt: number | null;
}

export function linkHealth({ stream, status, statusAt, now, staleS = 5, statusTimeoutS = 10 }: LinkHealthInput): LinkHealth {
  const lastFrameAt = status?.lastFrameAgeS != null && statusAt !== null ? statusAt - status.lastFrameAgeS : null;
  const down = (reason: string): LinkHealth => ({ down: true, reason, lastFrameAt });
  // Before any status (no drone, or a backend without zenoh) nothing is known: no alarm.
  if (!status || statusAt === null) return { down: false, reason: null, lastFrameAt: null };
  if (stream === "closed" || stream === "error") return down("the workbench's stream is closed");
  // `modd up` gave up the run: its last status says why, and no status follows it.
  if (status.gaveUp) return down(gaveUpWords(status.gaveUp));
  if (now - statusAt > statusTimeoutS) return down(`no status from the base station for ${Math.round(now - statusAt)} s`);
  // A deploy reconfigures the link for a moment: not a loss.
  if (!status.connected && status.state !== "configuring") return down(linkStateWords(status.state));
  if (lastFrameAt !== null && now - lastFrameAt > staleS) return down(`no frame from the drone for ${Math.round(now - lastFrameAt)} s`);
  return { down: false, reason: null, lastFrameAt };
}

/** Why a link that is not up is lost, in the operator's words (not the session's state names). */
export function linkStateWords(state: LinkStatus["state"] | null | undefined): string {
  switch (state) {
    case "connecting": return "the base station is trying to reach the drone";
    case "handshake": return "the drone has not yet answered the base station's key check";
    case "stopped": return "the base station stopped the link";
    default: return "the drone's link is down";
  }
}

/** "modd up gave up the run: subbroker exited (1); stopping the run: 5 restarts within 60 s". */
export function gaveUpWords(stop: SupervisorStop): string {
  const code = stop.exitCode === null ? "" : ` (${stop.exitCode})`;
  return `modd up gave up the run: ${stop.reason || `${stop.process} exited${code}`}`;
}

/** "12 s", "3 min 4 s", "2 h 5 min". */
export function formatAge(s: number): string {
  if (typeof s !== "number" || !Number.isFinite(s)) return "—";
  const t = Math.max(0, Math.round(s));
  if (t < 60) return `${t} s`;
  if (t < 3600) return `${Math.floor(t / 60)} min ${t % 60} s`;
  return `${Math.floor(t / 3600)} h ${Math.floor((t % 3600) / 60)} min`;
}
