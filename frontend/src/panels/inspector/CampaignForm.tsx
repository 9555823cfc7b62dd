/**
 * The campaign's form in the Inspector (shown with nothing or the platform
 * selected): a one-drone model made a campaign and back, its shared radio
 * channels and its vehicles added, renamed and removed, and each vehicle's
 * settings over the mission's (brokers, devices, link). Built from the
 * schema like the element forms, with the same fields (FieldInput) and the
 * diagnostics of `/campaign/...` under the field they name. Every change is
 * an `editCampaign` action of the editor's store (undo, autosave, live plan).
 */
import { useMemo, useState, type ReactNode } from "react";
import type { Campaign, Channel, ModdModel, Vehicle } from "../../core/model.gen";
import type { Diagnostic } from "../../core/diagnostics";
import type { CampaignEdit } from "../../core/campaign";
import {
  campaignFields, campaignPointer, deviceField, deviceSensors, messagesAt, messagesElsewhere, type CampaignFields,
} from "../../core/campaignForm";
import { getPath, type FieldSpec } from "../../core/schemaForm";
import { MODD_SCHEMA } from "../../core/schema";
import { canEditCampaign } from "../../core/roles";
import { useEditorStore, useModel, useRole } from "../../editor/useEditor";
import { useDiagnostics } from "../../editor/useFlowElements";
import { FieldInput } from "./FieldInput";

type Act = (edit: CampaignEdit) => void;
interface Ctx { diags: readonly Diagnostic[]; readOnly: boolean; act: Act }

const NO_TOPICS: never[] = [];
/** Fields grouped under a heading of their own (a vehicle's brokers and link). */
const GROUPS: Record<string, string> = { pubBroker: "PubBroker", subBroker: "SubBroker", link: "Link (over the mission's)" };

export function CampaignForm() {
  const store = useEditorStore();
  const model = useModel();
  const role = useRole();
  const diags = useDiagnostics();
  const fields = useMemo(() => campaignFields(MODD_SCHEMA, model), [model]);
  const ctx: Ctx = { diags, readOnly: !canEditCampaign(role), act: (edit) => store.dispatch({ type: "editCampaign", edit }) };
  const c = model.campaign;
  if (!c) {
    return (
      <section className="campaign-form" aria-label="Campaign">
        <h3>Campaign</h3>
        <p className="kind-help">This model is one drone. A campaign flies it, as the mission model, on several vehicles: each a drone of its own, with its own brokers, devices, link and radio channel.</p>
        {!ctx.readOnly && <button type="button" onClick={() => ctx.act({ op: "start" })}>Make it a campaign</button>}
      </section>
    );
  }
  const inside = [
    ...fields.campaign.map((f) => campaignPointer(f.path)),
    ...(c.channels ?? []).map((_, i) => campaignPointer(["channels", i])),
    ...c.vehicles.map((_, i) => campaignPointer(["vehicles", i])),
  ];
  return (
    <section className="campaign-form" aria-label="Campaign">
      <h3>Campaign {c.name}</h3>
      <p className="kind-help">{MODD_SCHEMA.$defs?.Campaign?.description}</p>
      {ctx.readOnly && <p className="readonly-note" role="note">Read-only in the {role} view: the system designer edits the campaign.</p>}
      <Errors messages={messagesElsewhere(diags, "/campaign", inside)} />
      <form onSubmit={(e) => e.preventDefault()}>
        <Fields ctx={ctx} specs={fields.campaign} owner={c} at={[]} />
        <Channels ctx={ctx} campaign={c} fields={fields} />
        <h4>Vehicles</h4>
        {c.vehicles.map((v, i) => <VehiclePart key={i} ctx={ctx} model={model} vehicle={v} index={i} fields={fields} />)}
        {!ctx.readOnly && (
          <p className="campaign-actions">
            <button type="button" onClick={() => ctx.act({ op: "addVehicle" })}>Add vehicle</button>{" "}
            <button type="button" onClick={() => ctx.act({ op: "end" })}>Back to one drone</button>
          </p>
        )}
      </form>
    </section>
  );
}

function Errors({ messages }: { messages: string[] }) {
  return <>{messages.map((m) => <div key={m} className="field-error" role="alert">{m}</div>)}</>;
}

/** The schema's fields of one part of the campaign (at `at`), each with the diagnostics at its pointer. */
function Fields({ ctx, specs, owner, at }: { ctx: Ctx; specs: FieldSpec[]; owner: object; at: (string | number)[] }) {
  return (
    <>
      {specs.map((spec) => (
        <FieldInput key={`${at.join("/")}/${spec.path.join(".")}`} spec={spec} value={getPath(owner, spec.path)} topics={NO_TOPICS}
          readOnly={ctx.readOnly} errors={messagesAt(ctx.diags, campaignPointer([...at, ...spec.path]))}
          onCommit={(value) => ctx.act({ op: "set", path: [...at, ...spec.path].map(String), value })} />
      ))}
    </>
  );
}

/** One part of the form, with its own heading, Remove button and the diagnostics no field of it holds. */
function Part({ ctx, title, at, held, onRemove, children }: {
  ctx: Ctx; title: string; at: (string | number)[]; held: string[]; onRemove?: () => void; children: ReactNode;
}) {
  return (
    <fieldset className="campaign-part" aria-label={title}>
      <legend>{title}</legend>
      <Errors messages={messagesElsewhere(ctx.diags, campaignPointer(at), held)} />
      {children}
      {!ctx.readOnly && onRemove && <button type="button" aria-label={`Remove ${title}`} onClick={onRemove}>Remove</button>}
    </fieldset>
  );
}

function Channels({ ctx, campaign, fields }: { ctx: Ctx; campaign: Campaign; fields: CampaignFields }) {
  const members = (ch: Channel) => campaign.vehicles.filter((v) => v.channel === ch.name).map((v) => v.name);
  return (
    <>
      <h4>Shared radio channels</h4>
      {!(campaign.channels ?? []).length && <p className="muted">None: each vehicle's link has its radio to itself.</p>}
      {(campaign.channels ?? []).map((ch, i) => (
        <Part key={i} ctx={ctx} title={`Channel ${ch.name}`} at={["channels", i]}
          held={fields.channel.map((f) => campaignPointer(["channels", i, ...f.path]))} onRemove={() => ctx.act({ op: "removeChannel", index: i })}>
          <Fields ctx={ctx} specs={fields.channel} owner={ch} at={["channels", i]} />
          <p className="muted">Vehicles on it: {members(ch).join(", ") || "none yet (choose it in a vehicle)"}</p>
        </Part>
      ))}
      {!ctx.readOnly && <button type="button" onClick={() => ctx.act({ op: "addChannel" })}>Add channel</button>}
    </>
  );
}

function VehiclePart({ ctx, model, vehicle, index, fields }: { ctx: Ctx; model: ModdModel; vehicle: Vehicle; index: number; fields: CampaignFields }) {
  const at = ["vehicles", index];
  const own = fields.vehicle.filter((f) => !(f.path[0] in GROUPS));
  const devices = deviceSensors(model, index);
  const deviceAt = (sensor: string) => (vehicle.devices ?? []).findIndex((d) => d.sensor === sensor);
  const held = [
    ...own.map((f) => campaignPointer([...at, ...f.path])),
    ...Object.keys(GROUPS).map((g) => campaignPointer([...at, g])),
    ...devices.filter((d) => deviceAt(d.sensor) >= 0).map((d) => campaignPointer([...at, "devices", deviceAt(d.sensor)])),
  ];
  return (
    <Part ctx={ctx} title={`Vehicle ${vehicle.name}`} at={at} held={held}
      onRemove={() => ctx.act({ op: "removeVehicle", index })}>
      <Fields ctx={ctx} specs={own} owner={vehicle} at={at} />
      {Object.entries(GROUPS).map(([group, title]) => (
        <VehicleGroup key={group} ctx={ctx} vehicle={vehicle} index={index} group={group} title={title}
          specs={fields.vehicle.filter((f) => f.path[0] === group)} />
      ))}
      {devices.map(({ sensor, mission }) => (
        <FieldInput key={`${index}/device/${sensor}`} spec={deviceField(MODD_SCHEMA, sensor, mission)} topics={NO_TOPICS} readOnly={ctx.readOnly}
          value={vehicle.devices?.find((d) => d.sensor === sensor)?.path}
          errors={deviceAt(sensor) < 0 ? [] : messagesAt(ctx.diags, campaignPointer([...at, "devices", deviceAt(sensor)]))}
          onCommit={(path) => ctx.act({ op: "setDevice", vehicle: index, sensor, path: path === undefined ? undefined : String(path) })} />
      ))}
    </Part>
  );
}

/** A vehicle's broker or link settings: folded while the vehicle keeps the mission's and nothing there is wrong. */
function VehicleGroup({ ctx, vehicle, index, group, title, specs }: {
  ctx: Ctx; vehicle: Vehicle; index: number; group: string; title: string; specs: FieldSpec[];
}) {
  const at = campaignPointer(["vehicles", index, group]);
  const troubled = messagesAt(ctx.diags, at).length > 0;
  const given = getPath(vehicle, [group]) !== undefined;
  // Opened by hand (or shown with a setting or a problem), it stays open while its last setting is cleared.
  const [open, setOpen] = useState(given || troubled);
  return (
    <details className="campaign-group" open={open || troubled} onToggle={(e) => setOpen(e.currentTarget.open)}>
      <summary>{title}{given ? "" : ": the mission's"}</summary>
      <Errors messages={messagesElsewhere(ctx.diags, at, specs.map((f) => campaignPointer(["vehicles", index, ...f.path])))} />
      <Fields ctx={ctx} specs={specs} owner={vehicle} at={["vehicles", index]} />
    </details>
  );
}
