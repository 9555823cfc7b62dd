/**
 * One live stream per drone for the whole workbench, shared by the link
 * banner, the monitor and the map: opened by the first user, closed when
 * the last one leaves. The workbench's link banner holds it for as long as
 * the project is open, so a chart's history (kept in the source's ring
 * buffers) survives switching panels, views and redeploys.
 *
 * @example
 *   const { source, state, link, linkAt } = useDroneStream("usv");
 */
import { useEffect, useMemo, useState } from "react";
import type { ConnectionState, DataSource, LinkStatus } from "../dataSources/types";
import { useServices, type Services } from "./services";

interface Entry { source: DataSource; users: number; link: LinkStatus | null; linkAt: number | null }
const shared = new WeakMap<Services, Map<string, Entry>>();

/** The drone's entry, created on first use; counted by the effects that use it. */
function entryFor(services: Services, drone: string): Entry {
  let byDrone = shared.get(services);
  if (!byDrone) { byDrone = new Map(); shared.set(services, byDrone); }
  let e = byDrone.get(drone);
  if (!e) {
    const entry: Entry = { source: services.openStream(drone), users: 0, link: null, linkAt: null };
    // The last status is kept here, so a panel opened later shows it at once.
    entry.source.onLinkStatus((s) => { entry.link = s; entry.linkAt = Date.now() / 1000; });
    byDrone.set(drone, entry);
    e = entry;
  }
  return e;
}

function release(services: Services, drone: string, e: Entry): void {
  e.users -= 1;
  if (e.users > 0) return;
  // Let go a moment later: a panel that unmounts and mounts again (StrictMode, a tab switch) keeps the stream.
  window.setTimeout(() => {
    if (e.users > 0) return;
    e.source.close();
    if (shared.get(services)?.get(drone) === e) shared.get(services)?.delete(drone);
  }, 1000);
}

export interface DroneStream {
  source: DataSource;
  state: ConnectionState;
  link: LinkStatus | null;
  /** When `link` arrived, seconds on the browser's clock. */
  linkAt: number | null;
}

export function useDroneStream(drone: string): DroneStream {
  const services = useServices();
  const entry = useMemo(() => entryFor(services, drone), [services, drone]);
  const [state, setState] = useState<ConnectionState>(entry.source.state);
  const [link, setLink] = useState<{ link: LinkStatus | null; at: number | null }>({ link: entry.link, at: entry.linkAt });
  useEffect(() => {
    entry.users += 1;
    const a = entry.source.onStateChange(setState);
    const b = entry.source.onLinkStatus((s) => setLink({ link: s, at: Date.now() / 1000 }));
    setState(entry.source.state);
    return () => { a(); b(); release(services, drone, entry); };
  }, [entry, services, drone]);
  return { source: entry.source, state, link: link.link, linkAt: link.at };
}
