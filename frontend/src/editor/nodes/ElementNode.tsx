/**
 * One diagram node: kind icon, name, detail line, plan badge, and markers for
 * errors, warnings and infeasibility (their messages in the tooltip and the
 * accessible label). Handles follow the data flow: a target on the left for
 * what flows in, a source on the right for what flows out.
 */
import { memo } from "react";
import { Handle, Position, type NodeProps } from "@xyflow/react";
import type { ElementKind } from "../../core/ids";
import type { ElementNode as ElementNodeType } from "./types";

const HAS_TARGET: Record<ElementKind, boolean> = {
  drone: false, sensor: true, topic: true, pubBroker: false, subBroker: true, link: false, publisher: false, subscriber: true,
};
const HAS_SOURCE: Record<ElementKind, boolean> = {
  drone: true, sensor: true, topic: true, pubBroker: true, subBroker: false, link: false, publisher: true, subscriber: false,
};
export const KIND_LABEL: Record<ElementKind, string> = {
  drone: "Drone", sensor: "Sensor", topic: "Measured variable", pubBroker: "PubBroker", subBroker: "SubBroker",
  link: "Link", publisher: "Publisher", subscriber: "Subscriber",
};
const ICON: Record<ElementKind, string> = {
  drone: "◆", sensor: "◎", topic: "∿", pubBroker: "⇉", subBroker: "⇇", link: "⇄", publisher: "▶", subscriber: "◀",
};

function ElementNodeView({ data, selected }: NodeProps<ElementNodeType>) {
  const m = data.markers;
  const problems = [...(m?.errors ?? []), ...(m?.infeasible ?? []).map((r) => `infeasible: ${r}`), ...(m?.warnings ?? [])];
  const state = m?.errors.length ? "error" : m?.infeasible.length ? "infeasible" : m?.warnings.length ? "warning" : "ok";
  return (
    <div
      className={`node node-${data.kind} node-${state}${selected ? " node-selected" : ""}${data.readOnly ? " node-readonly" : ""}`}
      title={problems.join("\n") || undefined}
      aria-label={`${KIND_LABEL[data.kind]} ${data.label}${problems.length ? `: ${problems.join("; ")}` : ""}`}
      data-testid={`node-${data.kind}`}
    >
      {HAS_TARGET[data.kind] && <Handle type="target" position={Position.Left} />}
      <div className="node-head">
        <span className="node-icon" aria-hidden>{ICON[data.kind]}</span>
        <span className="node-label">{data.label}</span>
        {state !== "ok" && <span className={`node-marker marker-${state}`} aria-hidden>{state === "warning" ? "!" : "✖"}</span>}
      </div>
      <div className="node-detail">{data.detail}</div>
      {m?.badge && <div className="node-badge">{m.badge}</div>}
      {HAS_SOURCE[data.kind] && <Handle type="source" position={Position.Right} />}
    </div>
  );
}

export const ElementNodeComponent = memo(ElementNodeView);
