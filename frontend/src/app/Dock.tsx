/**
 * The bottom dock: tabs over the lazily loaded panels, each in its own error
 * boundary, and optionally a second panel beside the tab's (map beside the
 * Monitor, say), both resizable; the arrangement is remembered per user and
 * role (core/dockLayout.ts) and reset in one click.
 */
import { useEffect, useRef, useState, type PointerEvent as ReactPointerEvent } from "react";
import { PANELS, type PanelInfo } from "../panels/registry";
import { PanelBoundary } from "../panels/PanelBoundary";
import { useEditor, useEditorStore } from "../editor/useEditor";
import { DEFAULT_LAYOUT, loadLayout, resetLayout, saveLayout, type DockLayout } from "../core/dockLayout";
import type { PanelId } from "../editor/store";

const IDS = PANELS.map((p) => p.id);

/** Follows the pointer until it is released (a divider being dragged). */
function dragWith(e: ReactPointerEvent, onMove: (ev: PointerEvent) => void): void {
  e.preventDefault();
  const up = () => { window.removeEventListener("pointermove", onMove); window.removeEventListener("pointerup", up); };
  window.addEventListener("pointermove", onMove);
  window.addEventListener("pointerup", up);
}

function Pane({ panel, role, style }: { panel: PanelInfo; role: "tabpanel" | "region"; style?: React.CSSProperties }) {
  const Component = panel.component;
  return (
    <div className="dock-pane" role={role} aria-label={panel.title} style={style}>
      <PanelBoundary key={panel.id} title={panel.title}><Component /></PanelBoundary>
    </div>
  );
}

export function Dock({ user = "" }: { user?: string }) {
  const store = useEditorStore();
  const active = useEditor((s) => s.panel);
  const role = useEditor((s) => s.wb.role);
  const panel = PANELS.find((p) => p.id === active) ?? PANELS[0];
  const [expanded, setExpanded] = useState(false);
  const [layout, setLayout] = useState<DockLayout>(() => loadLayout(window.localStorage, user, role, IDS));
  useEffect(() => { setLayout(loadLayout(window.localStorage, user, role, IDS)); }, [user, role]);
  const change = (next: Partial<DockLayout>) => setLayout((l) => {
    const merged = { ...l, ...next };
    saveLayout(window.localStorage, user, role, merged);
    return merged;
  });
  const body = useRef<HTMLDivElement>(null);
  const dock = useRef<HTMLElement>(null);
  const beside = layout.beside && layout.beside !== panel.id ? PANELS.find((p) => p.id === layout.beside) : undefined;
  const isDefault = JSON.stringify(layout) === JSON.stringify(DEFAULT_LAYOUT);

  return (
    <section ref={dock} className={`dock${expanded ? " dock-expanded" : ""}`} aria-label="Panels"
      style={expanded ? undefined : { height: layout.height }}>
      <div className="dock-resize" role="separator" aria-orientation="horizontal" aria-label="Resize the panels' height"
        onPointerDown={(e) => {
          const bottom = dock.current?.getBoundingClientRect().bottom ?? 0;
          dragWith(e, (ev) => change({ height: Math.min(900, Math.max(160, Math.round(bottom - ev.clientY))) }));
        }} />
      <div className="dock-tabs">
        <div role="tablist" className="dock-tablist">
          {PANELS.map((p) => (
            <button key={p.id} role="tab" aria-selected={p.id === panel.id} className={p.id === panel.id ? "active" : ""}
              onClick={() => store.patch({ panel: p.id })}>{p.title}</button>
          ))}
        </div>
        <select className="dock-beside" aria-label="Panel beside" title="Show a second panel beside this one"
          value={beside?.id ?? ""} onChange={(e) => change({ beside: (e.target.value || null) as PanelId | null })}>
          <option value="">+ beside</option>
          {PANELS.filter((p) => p.id !== panel.id).map((p) => <option key={p.id} value={p.id}>beside: {p.title}</option>)}
        </select>
        {!isDefault && (
          <button className="dock-reset" aria-label="Reset layout" title="Reset layout: one panel, the default height"
            onClick={() => setLayout(resetLayout(window.localStorage, user, role))}>↺</button>
        )}
        <button className="dock-toggle" aria-pressed={expanded} onClick={() => setExpanded((e) => !e)}>
          {expanded ? "Shrink panel" : "Expand panel"}
        </button>
      </div>
      <div ref={body} className={`dock-body${beside ? " dock-split" : ""}`}>
        <Pane panel={panel} role="tabpanel" style={beside ? { flexBasis: `${layout.split * 100}%` } : undefined} />
        {beside && (
          <>
            <div className="dock-divider" role="separator" aria-orientation="vertical" aria-label="Resize the panels' widths"
              tabIndex={0} aria-valuenow={Math.round(layout.split * 100)} aria-valuemin={20} aria-valuemax={80}
              onKeyDown={(e) => {
                if (e.key === "ArrowLeft") change({ split: Math.max(0.2, layout.split - 0.05) });
                if (e.key === "ArrowRight") change({ split: Math.min(0.8, layout.split + 0.05) });
              }}
              onPointerDown={(e) => {
                const box = body.current?.getBoundingClientRect();
                if (box) dragWith(e, (ev) => change({ split: Math.min(0.8, Math.max(0.2, (ev.clientX - box.left) / box.width)) }));
              }} />
            <Pane panel={beside} role="region" />
          </>
        )}
      </div>
    </section>
  );
}
