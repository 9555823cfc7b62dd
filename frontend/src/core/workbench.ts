/**
 * The editing session as one immutable state and a reducer: the model's
 * undo/redo history, the selection, the role of the current view and the last
 * refused edit. The editor's store holds one of these; everything here is
 * testable without React.
 *
 * Permission rule: an edit is applied only when the view's role may edit the
 * element kinds it touches; otherwise the state records why it was refused.
 */
import type { ModdModel, Position } from "./model.gen";
import type { Aggregation } from "./model.gen";
import { createHistory, push, undo, redo, reset, type History } from "./history";
import {
  EditError, addPublisher, addSensor, addSubscriber, addVariable, connect, disconnect,
  moveNodes, removeElements, renamedId, setField,
} from "./ops";
import { applyCampaignEdit, campaignEditKey, type CampaignEdit } from "./campaign";
import { copyElements, isEmptyFragment, pasteFragment, type Fragment } from "./clipboard";
import { parseId, type ElementKind } from "./ids";
import { canEdit, canEditCampaign, deniedParts, deniedPartsFor, editsAnything, partWords, refusalOfParts, type Role } from "./roles";

export interface WorkbenchState {
  history: History<ModdModel>;
  selection: string[];
  role: Role;
  clipboard: Fragment | null;
  /** Why the last edit was refused, until the next successful edit. */
  notice: string | null;
}

export type Action =
  | { type: "load"; model: ModdModel }
  /** Replace the whole model (text applied to the diagram): one undo step, only parts the role owns may change. */
  /** Something the user must read about their last action (a dropped file not applied). */
  | { type: "notify"; notice: string }
  /** A whole model (text applied, a file dropped). With `roles` (the user's), it is checked
   * against what the user may change, not only the view: an admin applies anything. */
  | { type: "replaceModel"; model: ModdModel; roles?: readonly Role[] }
  | { type: "setRole"; role: Role }
  | { type: "select"; ids: string[] }
  | { type: "addSensor"; pos?: Position }
  | { type: "addVariable"; sensor: string; pos?: Position }
  | { type: "addPublisher"; pos?: Position }
  | { type: "addSubscriber"; topic?: string; periodS?: string; aggregation?: Aggregation; pos?: Position }
  | { type: "remove"; ids: string[] }
  | { type: "connect"; source: string; target: string }
  | { type: "disconnect"; source: string; target: string }
  | { type: "setField"; id: string; path: string[]; value: unknown }
  /** An edit of the campaign (core/campaign.ts): the Inspector's campaign form. */
  | { type: "editCampaign"; edit: CampaignEdit }
  | { type: "move"; positions: Record<string, Position> }
  | { type: "copy"; ids: string[] }
  /** Copy and paste in one step, leaving the clipboard as it is (a subscription asked twice). */
  | { type: "duplicate"; ids: string[] }
  | { type: "paste" }
  | { type: "undo" }
  | { type: "redo" }
  | { type: "dismissNotice" };

export function initialState(model: ModdModel, role: Role): WorkbenchState {
  return { history: createHistory(model), selection: [], role, clipboard: null, notice: null };
}

export const currentModel = (s: WorkbenchState): ModdModel => s.history.present;

function kindOf(id: string): ElementKind | null {
  return parseId(id)?.kind ?? null;
}

function refuse(s: WorkbenchState, notice: string): WorkbenchState {
  return { ...s, notice };
}

function commit(s: WorkbenchState, model: ModdModel, opts: { select?: string[]; coalesce?: string } = {}): WorkbenchState {
  return {
    ...s,
    history: push(s.history, model, opts.coalesce),
    selection: opts.select ?? s.selection,
    notice: null,
  };
}

function allowed(s: WorkbenchState, kind: ElementKind): boolean {
  return canEdit(s.role, kind);
}

const denied = (role: Role, what: string) => `the ${role} view cannot edit ${what}`;

function edit(s: WorkbenchState, a: Action): WorkbenchState {
  const m = currentModel(s);
  switch (a.type) {
    case "addSensor": {
      if (!allowed(s, "sensor")) return refuse(s, denied(s.role, "sensors"));
      const r = addSensor(m, undefined, a.pos);
      return commit(s, r.model, { select: [r.id] });
    }
    case "addVariable": {
      if (!allowed(s, "topic")) return refuse(s, denied(s.role, "measured variables"));
      const r = addVariable(m, a.sensor, undefined, "NONE", a.pos);
      return commit(s, r.model, { select: [r.id] });
    }
    case "addPublisher": {
      if (!allowed(s, "publisher")) return refuse(s, denied(s.role, "publishers"));
      const r = addPublisher(m, undefined, "1.0", a.pos);
      return commit(s, r.model, { select: [r.id] });
    }
    case "addSubscriber": {
      if (!allowed(s, "subscriber")) return refuse(s, denied(s.role, "subscribers"));
      const r = addSubscriber(m, { topic: a.topic, periodS: a.periodS, aggregation: a.aggregation }, a.pos);
      return commit(s, r.model, { select: [r.id] });
    }
    case "remove": {
      const mine = a.ids.filter((id) => { const k = kindOf(id); return k !== null && allowed(s, k); });
      if (mine.length === 0) return refuse(s, denied(s.role, "the selection"));
      const r = removeElements(m, mine);
      const next = commit(s, r.model, { select: [] });
      return r.refused.length ? { ...next, notice: r.refused.join("; ") } : next;
    }
    case "connect": case "disconnect": {
      const sk = kindOf(a.source);
      const edgeOwner: ElementKind = sk === "publisher" ? "publisher" : "subscriber";
      if (!allowed(s, edgeOwner)) return refuse(s, denied(s.role, edgeOwner === "publisher" ? "what publishers publish" : "subscriptions"));
      const model = a.type === "connect" ? connect(m, a.source, a.target) : disconnect(m, a.source, a.target);
      return commit(s, model);
    }
    case "setField": {
      const k = kindOf(a.id);
      if (!k || !allowed(s, k)) return refuse(s, denied(s.role, "this element"));
      const model = setField(m, a.id, a.path, a.value);
      const renamed = a.path.length === 1 && a.path[0] === "name" && typeof a.value === "string";
      const newId = renamed ? renamedId(a.id, a.value as string) : a.id;
      const select = s.selection.map((x) => (x === a.id ? newId : x));
      return commit(s, model, { select, coalesce: `field:${newId}:${a.path.join(".")}` });
    }
    case "editCampaign": {
      if (!canEditCampaign(s.role)) return refuse(s, denied(s.role, "the campaign"));
      return commit(s, applyCampaignEdit(m, a.edit), { coalesce: campaignEditKey(a.edit) });
    }
    case "replaceModel": {
      if (a.roles) {
        const denied = deniedPartsFor(a.roles, m, a.model);
        if (denied.length) return refuse(s, refusalOfParts(denied, a.roles));
        return commit(s, a.model, { select: [] });
      }
      const denied = deniedParts(s.role, m, a.model);
      if (denied.length) return refuse(s, `the ${s.role} view cannot change ${denied.map(partWords).join(", ")}`);
      return commit(s, a.model, { select: [] });
    }
    case "move":
      // Anyone may arrange the diagram: the layout is presentation, not model.
      return commit(s, moveNodes(m, a.positions));
    case "duplicate":
    case "paste": {
      const c = a.type === "paste" ? s.clipboard : copyElements(m, a.ids);
      if (!c || isEmptyFragment(c)) return s;
      if (c.sensors.length && !allowed(s, "sensor")) return refuse(s, denied(s.role, "sensors"));
      if (c.publishers.length && !allowed(s, "publisher")) return refuse(s, denied(s.role, "publishers"));
      if (c.subscribers.length && !allowed(s, "subscriber")) return refuse(s, denied(s.role, "subscribers"));
      const r = pasteFragment(m, c);
      return commit(s, r.model, { select: r.ids });
    }
    default:
      return s;
  }
}

/** The reducer. Edits that the model refuses (EditError) leave the model unchanged and set `notice`. */
export function reduce(s: WorkbenchState, a: Action): WorkbenchState {
  switch (a.type) {
    case "load": return { ...s, history: reset(s.history, a.model), selection: [], notice: null };
    case "setRole": return { ...s, role: a.role, notice: null };
    case "select": return sameIds(s.selection, a.ids) ? s : { ...s, selection: a.ids };
    // A view that edits nothing (the operator's) changes nothing: no undo, redo or copy either.
    case "undo": return readOnlyView(s) ? refuse(s, denied(s.role, "the model (no undo)")) : { ...s, history: undo(s.history), notice: null };
    case "redo": return readOnlyView(s) ? refuse(s, denied(s.role, "the model (no redo)")) : { ...s, history: redo(s.history), notice: null };
    case "copy": return readOnlyView(s) ? s : { ...s, clipboard: copyElements(currentModel(s), a.ids) };
    case "dismissNotice": return { ...s, notice: null };
    case "notify": return { ...s, notice: a.notice };
    default:
      try {
        const next = edit(s, a);
        // The backend's save rule, applied at once: an edit that would change a part
        // another role owns (e.g. a sensor rename reaching subscriptions) is refused here.
        const before = currentModel(s);
        const after = currentModel(next);
        const checked = a.type === "replaceModel" && a.roles !== undefined; // against the user's roles
        if (a.type !== "move" && !checked && after !== before) {
          const denied = deniedParts(s.role, before, after);
          if (denied.length) return refuse(s, `this edit changes ${denied.map(partWords).join(", ")}, which the ${s.role} view may not change`);
        }
        return next;
      } catch (e) {
        if (e instanceof EditError) return refuse(s, e.message);
        throw e;
      }
  }
}

/** Whether the view's role may edit nothing at all (the operator view). */
export function readOnlyView(s: WorkbenchState): boolean {
  return !editsAnything(s.role);
}

function sameIds(a: readonly string[], b: readonly string[]): boolean {
  return a.length === b.length && a.every((x, i) => x === b[i]);
}
