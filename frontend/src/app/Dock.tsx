/** The bottom dock: tabs over the lazily loaded panels, each in its own error boundary. */
import { useState } from "react";
import { PANELS } from "../panels/registry";
import { PanelBoundary } from "../panels/PanelBoundary";
import { useEditor, useEditorStore } from "../editor/useEditor";

export function Dock() {
  const store = useEditorStore();
  const active = useEditor((s) => s.panel);
  const panel = PANELS.find((p) => p.id === active) ?? PANELS[0];
  const Component = panel.component;
  const [expanded, setExpanded] = useState(false);
  return (
    <section className={`dock${expanded ? " dock-expanded" : ""}`} aria-label="Panels">
      <div className="dock-tabs">
        <div role="tablist" className="dock-tablist">
          {PANELS.map((p) => (
            <button key={p.id} role="tab" aria-selected={p.id === panel.id} className={p.id === panel.id ? "active" : ""}
              onClick={() => store.patch({ panel: p.id })}>{p.title}</button>
          ))}
        </div>
        <button className="dock-toggle" aria-pressed={expanded} onClick={() => setExpanded((e) => !e)}>
          {expanded ? "Shrink panel" : "Expand panel"}
        </button>
      </div>
      <div className="dock-body" role="tabpanel" aria-label={panel.title}>
        <PanelBoundary key={panel.id} title={panel.title}><Component /></PanelBoundary>
      </div>
    </section>
  );
}
