// @vitest-environment jsdom
import { describe, expect, it } from "vitest";
import { sceneShowsOnlyItsOwn } from "./sceneCover";

function page(html: string): Document {
  const doc = document.implementation.createHTMLDocument("scene");
  doc.body.innerHTML = html;
  return doc;
}

describe("the 3D scene's cover", () => {
  it("stays while the page is not drawn or shows viser's developer controls", () => {
    expect(sceneShowsOnlyItsOwn(null)).toBe(false);
    expect(sceneShowsOnlyItsOwn(page("<script></script>"))).toBe(false);
    // viser connecting: its address, Save Canvas, Reset View, Dev Settings
    expect(sceneShowsOnlyItsOwn(page(`<div><input value="ws://127.0.0.1/scene"><button><span>⬇</span> Save Canvas</button>
      <button>Reset View</button><label><input type="checkbox"> Dev Settings</label></div>`))).toBe(false);
  });

  it("goes once the scene's own panel has put them away", () => {
    expect(sceneShowsOnlyItsOwn(page(`<button aria-label="settings"></button><p><b>Drone tracks</b>: each point…</p>
      <div style="display: none"><button>Save Canvas</button><label>Dev Settings</label></div>`))).toBe(true);
    expect(sceneShowsOnlyItsOwn(page(`<button aria-label="settings"></button><div hidden><button>Save Canvas</button></div>`))).toBe(true);
  });
});
