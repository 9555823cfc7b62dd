/**
 * Campaign edits (the Inspector's campaign form): a one-drone model made the
 * mission model of several vehicles and back, vehicles and shared radio
 * channels added, renamed and removed, each vehicle's settings over the
 * mission's. Each edit is pure (a new model, the input unchanged) and goes
 * through the workbench reducer (`editCampaign`): one undo step, autosaved
 * and planned like any other. References follow: a channel renamed or
 * removed is renamed or dropped in its vehicles.
 *
 * @example
 *   let m = applyCampaignEdit(oneDrone, { op: "start" });   // vehicles usv_1, usv_2
 *   m = applyCampaignEdit(m, { op: "set", path: ["vehicles", "1", "channel"], value: "ch_1" });
 */
import type { Campaign, DeviceOverride, ModdModel, Vehicle } from "./model.gen";
import { EditError, setIn } from "./ops";
import { freshName } from "./templates";

export type CampaignEdit =
  /** A one-drone model becomes the mission model of its first two vehicles. */
  | { op: "start" }
  /** Back to one drone: the campaign is removed (the mission model stays). */
  | { op: "end" }
  /** A field inside the campaign, by path (`["vehicles", "0", "pubBroker", "endpoint", "port"]`); undefined removes it. */
  | { op: "set"; path: string[]; value: unknown }
  | { op: "addVehicle" }
  | { op: "removeVehicle"; index: number }
  | { op: "addChannel" }
  | { op: "removeChannel"; index: number }
  /** A vehicle's device for a sensor of the mission model; undefined: the mission's. */
  | { op: "setDevice"; vehicle: number; sensor: string; path: string | undefined };

/** Room for a suffix in a name made from the drone's (names have at most 64 characters). */
const NAME_ROOM = 52;
/** Largest port a new vehicle's PubBroker is given. */
const MAX_PORT = 65535;

/** A port no vehicle's PubBroker (nor the mission's) uses: one past the highest. */
function nextPubPort(m: ModdModel, c: Campaign): number {
  const used = [m.pubBroker.endpoint.port, ...c.vehicles.map((v) => v.pubBroker?.endpoint.port ?? 0)];
  const next = Math.max(...used) + 1;
  return next <= MAX_PORT ? next : Math.min(...used) - 1;
}

/** A new vehicle: the first uses the mission's brokers; each other gets a PubBroker endpoint of its own
 * (two vehicles on one PubBroker endpoint is an error: each vehicle carries its own). */
function newVehicle(m: ModdModel, c: Campaign): Vehicle {
  const name = freshName(m.drone.name.slice(0, NAME_ROOM), c.vehicles.map((v) => v.name));
  if (c.vehicles.length === 0) return { name };
  return { name, pubBroker: { endpoint: { host: m.pubBroker.endpoint.host, port: nextPubPort(m, c) } } };
}

function start(m: ModdModel): void {
  if (m.campaign) throw new EditError("the model is already a campaign");
  const c: Campaign = { name: `${m.drone.name.slice(0, NAME_ROOM)}_campaign`, vehicles: [] };
  c.vehicles.push(newVehicle(m, c));
  c.vehicles.push(newVehicle(m, c));
  m.campaign = c;
}

function campaignOf(m: ModdModel): Campaign {
  if (!m.campaign) throw new EditError("the model is one drone: make it a campaign first");
  return m.campaign;
}

function index<T>(list: readonly T[] | undefined, i: number, what: string): T {
  const found = list?.[i];
  if (found === undefined) throw new EditError(`no ${what} ${i + 1}`);
  return found;
}

/** A channel renamed: its vehicles follow. */
function renameChannel(c: Campaign, i: number, name: unknown): void {
  const old = index(c.channels, i, "channel").name;
  for (const v of c.vehicles) if (v.channel === old && typeof name === "string" && name !== "") v.channel = name;
}

function setDevice(c: Campaign, vehicle: number, sensor: string, path: string | undefined): void {
  const v = index(c.vehicles, vehicle, "vehicle");
  const others: DeviceOverride[] = (v.devices ?? []).filter((d) => d.sensor !== sensor);
  const at = (v.devices ?? []).findIndex((d) => d.sensor === sensor);
  const devices = path === undefined || path === "" ? others
    : at < 0 ? [...others, { sensor, path }] : (v.devices ?? []).map((d, j) => (j === at ? { sensor, path } : d));
  if (devices.length) v.devices = devices;
  else delete v.devices;
}

function removeChannel(c: Campaign, i: number): void {
  const gone = index(c.channels, i, "channel").name;
  c.channels = c.channels!.filter((_, j) => j !== i);
  if (!c.channels.length) delete c.channels;
  for (const v of c.vehicles) if (v.channel === gone) delete v.channel;
}

function edit(m: ModdModel, e: CampaignEdit): void {
  if (e.op === "start") return start(m);
  if (e.op === "end") { campaignOf(m); delete m.campaign; return; }
  const c = campaignOf(m);
  switch (e.op) {
    case "set":
      if (e.path.length === 0) throw new EditError("no field given");
      if (e.path[0] === "channels" && e.path.length === 3 && e.path[2] === "name") renameChannel(c, Number(e.path[1]), e.value);
      setIn(c as unknown as Record<string, unknown>, e.path, e.value);
      return;
    case "addVehicle":
      if (c.vehicles.length >= 100) throw new EditError("a campaign has at most 100 vehicles");
      c.vehicles.push(newVehicle(m, c));
      return;
    case "removeVehicle":
      index(c.vehicles, e.index, "vehicle");
      if (c.vehicles.length === 1) throw new EditError("a campaign has at least one vehicle: make it one drone instead");
      c.vehicles = c.vehicles.filter((_, j) => j !== e.index);
      return;
    case "addChannel":
      if ((c.channels?.length ?? 0) >= 100) throw new EditError("a campaign has at most 100 channels");
      c.channels = [...(c.channels ?? []), { name: freshName("ch", (c.channels ?? []).map((x) => x.name)) }];
      return;
    case "removeChannel": return removeChannel(c, e.index);
    case "setDevice": return setDevice(c, e.vehicle, e.sensor, e.path);
  }
}

/** The model with the campaign edit applied; throws EditError when the edit makes no sense. */
export function applyCampaignEdit(model: ModdModel, e: CampaignEdit): ModdModel {
  const m = structuredClone(model);
  edit(m, e);
  return m;
}

/** The undo key of an edit: typing in one field is one undo step. */
export function campaignEditKey(e: CampaignEdit): string | undefined {
  if (e.op === "set") return `campaign:${e.path.join(".")}`;
  if (e.op === "setDevice") return `campaign:vehicles.${e.vehicle}.device.${e.sensor}`;
  return undefined;
}
