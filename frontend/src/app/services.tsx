/**
 * What the UI gets from outside, through context: the backend client and the
 * live data source factory. Created once in main.tsx from the page's origin;
 * tests can provide fakes.
 */
import { createContext, useContext } from "react";
import type { Api } from "../api/client";
import type { DataSource } from "../dataSources/types";

export interface Services {
  api: Api;
  /** Opens the stream WebSocket of a drone (one per drone, shared by panels). */
  openStream: (drone: string) => DataSource;
}

export const ServicesContext = createContext<Services | null>(null);

export function useServices(): Services {
  const s = useContext(ServicesContext);
  if (!s) throw new Error("useServices: no ServicesContext provider");
  return s;
}
