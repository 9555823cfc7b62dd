/** The bottom dock: tabs over the lazily loaded panels, each in its own error boundary. */
import { PANELS } from "../panels/registry";
import { PanelBoundary } from "../panels/PanelBoundary";
import { useEditor, useEditorStore } from "../editor/useEditor";

export function Dock() {
  const store = useEditorStore();
  const active = useEditor((s) => s.panel);
  const panel = PANELS.find((p) => p.id === active) ?? PANELS[0];
  const Component = panel.component;
  return (
    <section className="dock" aria-label="Panels">
      <div className="dock-tabs" role="tablist">
        {PANELS.map((p) => (
          <button key={p.id} role="tab" aria-selected={p.id === panel.id} className={p.id === panel.id ? "active" : ""}
            onClick={() => store.patch({ panel: p.id })}>{p.title}</button>
        ))}
      </div>
      <div className="dock-body" role="tabpanel" aria-label={panel.title}>
        <PanelBoundary key={panel.id} title={panel.title}><Component /></PanelBoundary>
      </div>
    </section>
  );
}
