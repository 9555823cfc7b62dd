/**
 * The drone the per-drone panels (Monitor, Map, the link banner) show: the
 * project's one drone, or, for a campaign, the vehicle chosen in the Fleet
 * panel (its first until one is chosen). One choice for the whole page.
 *
 * @example
 *   focusDrone("usv2");
 *   const drone = useDroneName(); // "usv2" when the campaign has a vehicle usv2
 */
import { useSyncExternalStore } from "react";
import type { ModdModel } from "../core/model.gen";
import { useModel } from "../editor/useEditor";

let focused: string | null = null;
const listeners = new Set<() => void>();

export function focusDrone(name: string): void {
  focused = name;
  listeners.forEach((l) => l());
}

function subscribe(listener: () => void): () => void {
  listeners.add(listener);
  return () => { listeners.delete(listener); };
}

/** The drones a model deploys to: its campaign's vehicles, or its one drone (modd_model.campaign.drone_names). */
export function droneNames(model: ModdModel): string[] {
  const vehicles = model.campaign?.vehicles.map((v) => v.name) ?? [];
  return vehicles.length ? vehicles : [model.drone.name];
}

/** Which of the model's drones is shown, given the page's choice. */
export function shownDrone(model: ModdModel, choice: string | null): string {
  const names = droneNames(model);
  return choice !== null && names.includes(choice) ? choice : names[0];
}

export function useDroneName(): string {
  const model = useModel();
  const choice = useSyncExternalStore(subscribe, () => focused);
  return shownDrone(model, choice);
}
