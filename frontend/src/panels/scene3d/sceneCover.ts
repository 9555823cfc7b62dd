/**
 * viser's page shows its developer controls (Save Canvas, Dev Settings, the
 * server's address) until it has connected and received the scene's own
 * panel, the legend (backend scene.py), which puts them behind its settings
 * button. The 3D panel covers the page until then: "Connecting…", never those
 * controls. Read from the page's document (same origin: the backend's /scene/
 * proxy).
 *
 * @example
 *   sceneShowsOnlyItsOwn(iframe.contentDocument) // false while viser connects
 */
export const DEVELOPER_CONTROLS = ["Save Canvas", "Dev Settings"];

/** Whether an element is drawn (checkVisibility where the browser has it; else no hidden or undisplayed ancestor). */
function drawn(el: Element): boolean {
  if (typeof el.checkVisibility === "function") return el.checkVisibility({ visibilityProperty: true });
  for (let e: Element | null = el; e; e = e.parentElement) {
    const style = (e.ownerDocument.defaultView ?? window).getComputedStyle(e);
    if (e.hasAttribute("hidden") || style.display === "none" || style.visibility === "hidden") return false;
  }
  return true;
}

/**
 * Whether the scene's page is drawn and shows nothing but the scene and its
 * own panel: some control is drawn, and none of viser's developer controls.
 */
export function sceneShowsOnlyItsOwn(doc: Document | null | undefined): boolean {
  if (!doc?.body) return false;
  const buttons = [...doc.querySelectorAll("button, label")].filter(drawn);
  if (!buttons.some((b) => b.tagName === "BUTTON")) return false; // not drawn yet
  return !buttons.some((b) => DEVELOPER_CONTROLS.includes((b.textContent ?? "").trim()));
}
