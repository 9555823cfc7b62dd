import type { Node } from "@xyflow/react";
import type { ElementKind } from "../../core/ids";
import type { NodeMarkers } from "../../core/markers";

/** Data of every diagram node; the node's `type` is its element kind. */
export type ElementData = {
  kind: ElementKind;
  label: string;
  detail: string;
  markers: NodeMarkers | undefined;
  /** The current view's role may not edit this element. */
  readOnly: boolean;
};

export type ElementNode = Node<ElementData, ElementKind>;
