/**
 * The drone's link health (core/linkHealth), re-judged every second on the
 * browser's clock, with the seconds since its last frame.
 */
import { useDroneName } from "./fleetFocus";
import { useEffect, useState } from "react";
import { linkHealth, type LinkHealth } from "../core/linkHealth";
import { useEditor } from "../editor/useEditor";
import { useDroneStream, type DroneStream } from "./useDroneStream";

export interface LiveLink extends LinkHealth {
  stream: DroneStream;
  /** Seconds since the last frame (null: unknown). */
  sinceLastFrameS: number | null;
}

export function useLinkHealth(): LiveLink {
  const drone = useDroneName();
  const stream = useDroneStream(drone);
  // A plan with long gaps between messages is not a loss: wait two hyperperiods (at least 5 s).
  const hyper = Number(useEditor((s) => s.plan.lastValid?.hyperperiod_s ?? 0)) || 0;
  const [now, setNow] = useState(() => Date.now() / 1000);
  useEffect(() => {
    const t = window.setInterval(() => setNow(Date.now() / 1000), 1000);
    return () => window.clearInterval(t);
  }, []);
  const h = linkHealth({ stream: stream.state, status: stream.link, statusAt: stream.linkAt, now, staleS: Math.max(5, 2 * hyper) });
  return { ...h, stream, sinceLastFrameS: h.lastFrameAt === null ? null : Math.max(0, now - h.lastFrameAt) };
}
