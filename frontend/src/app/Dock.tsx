/**
 * The bottom dock: tabs over the lazily loaded panels, each in its own error
 * boundary, and optionally one or two more panels with the tab's (map and Plan
 * beside the Monitor, say), side by side or stacked, resizable by their
 * dividers; the arrangement is remembered per user and role
 * (core/dockLayout.ts) and reset in one click.
 */
import { Fragment, useEffect, useRef, useState, type PointerEvent as ReactPointerEvent } from "react";
import { PANELS, panelTabs, type PanelInfo } from "../panels/registry";
import { currentModel } from "../core/workbench";
import { PanelBoundary } from "../panels/PanelBoundary";
import { useEditor, useEditorStore } from "../editor/useEditor";
import { isDefault, loadLayout, moveDivider, resetLayout, saveLayout, setBeside, type DockLayout } from "../core/dockLayout";
import type { PanelId } from "../editor/store";
import { NamedLayouts } from "./NamedLayouts";

const IDS = PANELS.map((p) => p.id);

/** Follows the pointer until it is released (a divider being dragged). */
function dragWith(e: ReactPointerEvent, onMove: (ev: PointerEvent) => void): void {
  e.preventDefault();
  const up = () => { window.removeEventListener("pointermove", onMove); window.removeEventListener("pointerup", up); };
  window.addEventListener("pointermove", onMove);
  window.addEventListener("pointerup", up);
}

function Pane({ panel, role, share }: { panel: PanelInfo; role: "tabpanel" | "region"; share: number | null }) {
  const Component = panel.component;
  return (
    <div className="dock-pane" role={role} aria-label={panel.title} style={share === null ? undefined : { flexBasis: `${share * 100}%` }}>
      <PanelBoundary key={panel.id} title={panel.title}><Component /></PanelBoundary>
    </div>
  );
}

/** The choice of the panel in place `index` with the tab's ("none": the first option), after its words. */
function BesideSelect({ index, label, empty, layout, active, onChange }: {
  index: number; label: string; empty: string; layout: DockLayout; active: PanelId; onChange: (l: DockLayout) => void;
}) {
  const others = layout.beside.filter((_, i) => i !== index);
  return (
    <label>{empty}
      <select className="dock-beside" aria-label={label}
        value={layout.beside[index] ?? ""} onChange={(e) => onChange(setBeside(layout, index, (e.target.value || null) as PanelId | null))}>
        <option value="">none</option>
        {PANELS.filter((p) => p.id !== active && !others.includes(p.id)).map((p) => <option key={p.id} value={p.id}>{p.title}</option>)}
      </select>
    </label>
  );
}

/** The divider after pane `index`: dragged or moved by the arrow keys, it trades room between its two panes. */
function Divider({ index, layout, body, onMove }: {
  index: number; layout: DockLayout; body: React.RefObject<HTMLDivElement | null>; onMove: (sizes: number[]) => void;
}) {
  const stacked = layout.stacked;
  const [less, more] = stacked ? ["ArrowUp", "ArrowDown"] : ["ArrowLeft", "ArrowRight"];
  const before = layout.sizes.slice(0, index).reduce((a, b) => a + b, 0);
  return (
    <div className="dock-divider" role="separator" aria-orientation={stacked ? "horizontal" : "vertical"} tabIndex={0}
      aria-label={stacked ? `Resize the stacked panels (${index + 1})` : `Resize the panels' widths (${index + 1})`}
      aria-valuenow={Math.round((before + layout.sizes[index]) * 100)} aria-valuemin={0} aria-valuemax={100}
      onKeyDown={(e) => {
        if (e.key !== less && e.key !== more) return;
        e.preventDefault();
        onMove(moveDivider(layout.sizes, index, e.key === less ? -0.05 : 0.05));
      }}
      onPointerDown={(e) => {
        const box = body.current?.getBoundingClientRect();
        if (!box) return;
        dragWith(e, (ev) => {
          const at = stacked ? (ev.clientY - box.top) / box.height : (ev.clientX - box.left) / box.width;
          onMove(moveDivider(layout.sizes, index, at - before - layout.sizes[index]));
        });
      }} />
  );
}

export function Dock({ user = "" }: { user?: string }) {
  const store = useEditorStore();
  const active = useEditor((s) => s.panel);
  const role = useEditor((s) => s.wb.role);
  const campaign = useEditor((s) => currentModel(s.wb).campaign !== undefined);
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
  // A panel chosen to go with the tab's is not shown twice when it is the tab's own.
  const beside = layout.beside.filter((id) => id !== panel.id).flatMap((id) => PANELS.filter((p) => p.id === id));
  const fits = beside.length === layout.beside.length;
  const share = (i: number) => (fits ? layout.sizes[i] : 1 / (beside.length + 1));

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
          {panelTabs(campaign, panel.id).map((p) => (
            <button key={p.id} role="tab" aria-selected={p.id === panel.id} className={p.id === panel.id ? "active" : ""}
              onClick={() => store.patch({ panel: p.id })}>{p.title}</button>
          ))}
        </div>
        <details className="dock-layout">
          <summary aria-label="Panel layout" title="Panel layout: more panels with this one, side by side or stacked">⊞</summary>
          <div className="dock-layout-menu" role="group" aria-label="Panel layout">
            <BesideSelect index={0} label="Panel beside" empty="With this one " layout={layout} active={panel.id} onChange={change} />
            {layout.beside.length > 0 && (
              <>
                <BesideSelect index={1} label="Third panel" empty="and " layout={layout} active={panel.id} onChange={change} />
                <label><input type="checkbox" checked={layout.stacked} onChange={(e) => change({ stacked: e.target.checked })} /> Stacked</label>
              </>
            )}
            <NamedLayouts user={user} role={role} panels={IDS} current={{ panel: panel.id, layout }}
              onApply={(named) => { store.patch({ panel: named.panel }); change(named.layout); }} />
            <button type="button" onClick={() => setLayout(resetLayout(window.localStorage, user, role))}>Reset to default</button>
          </div>
        </details>
        {!isDefault(layout) && (
          <button className="dock-icon" aria-label="Reset layout" title="Reset layout: one panel, the default height"
            onClick={() => setLayout(resetLayout(window.localStorage, user, role))}>↺</button>
        )}
        <button className="dock-toggle" aria-pressed={expanded} onClick={() => setExpanded((e) => !e)}>
          {expanded ? "Shrink panel" : "Expand panel"}
        </button>
      </div>
      <div ref={body} className={`dock-body${beside.length ? ` dock-split${layout.stacked ? " dock-stacked" : ""}` : ""}`}>
        <Pane panel={panel} role="tabpanel" share={beside.length ? share(0) : null} />
        {beside.map((p, i) => (
          <Fragment key={p.id}>
            {fits ? <Divider index={i} layout={layout} body={body} onMove={(sizes) => change({ sizes })} />
              : <div className="dock-divider" aria-hidden />}
            <Pane panel={p} role="region" share={share(i + 1)} />
          </Fragment>
        ))}
      </div>
    </section>
  );
}
