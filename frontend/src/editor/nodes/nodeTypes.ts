import type { NodeTypes } from "@xyflow/react";
import { ElementNodeComponent } from "./ElementNode";

/** At module scope so xyflow sees one stable object (it warns and re-mounts otherwise). */
export const nodeTypes: NodeTypes = {
  drone: ElementNodeComponent,
  sensor: ElementNodeComponent,
  topic: ElementNodeComponent,
  pubBroker: ElementNodeComponent,
  subBroker: ElementNodeComponent,
  publisher: ElementNodeComponent,
  subscriber: ElementNodeComponent,
};
