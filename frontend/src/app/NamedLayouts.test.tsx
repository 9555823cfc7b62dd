// @vitest-environment jsdom
import { act, cleanup, fireEvent, render, screen } from "@testing-library/react";
import { afterEach, describe, expect, it, vi } from "vitest";
import { layoutFile, type NamedLayout } from "../core/namedLayouts";
import { NamedLayouts } from "./NamedLayouts";

const PANELS = ["plan", "monitor", "map"];
const current: NamedLayout = { panel: "monitor", layout: { beside: ["map"], stacked: false, sizes: [0.5, 0.5], height: 360 } };

function setup() {
  window.localStorage.clear();
  const onApply = vi.fn();
  render(<NamedLayouts user="ana" role="scientist" panels={PANELS} current={current} onApply={onApply} />);
  return onApply;
}

const importFile = async (text: string, name = "l.json") => {
  const input = screen.getByLabelText("Import layout file");
  await act(async () => { fireEvent.change(input, { target: { files: [new File([text], name, { type: "application/json" })] } }); });
};

afterEach(cleanup);

describe("NamedLayouts", () => {
  it("saves the current layout under a name and switches back to it", () => {
    const onApply = setup();
    fireEvent.change(screen.getByLabelText("Layout name"), { target: { value: "Survey" } });
    fireEvent.click(screen.getByRole("button", { name: "Save as" }));
    expect(screen.getByRole("status").textContent).toMatch(/Saved “Survey”/);
    fireEvent.change(screen.getByLabelText("Named layout"), { target: { value: "" } });
    fireEvent.change(screen.getByLabelText("Named layout"), { target: { value: "Survey" } });
    expect(onApply).toHaveBeenCalledWith(current);
    fireEvent.click(screen.getByRole("button", { name: "Delete" }));
    expect(screen.queryByRole("option", { name: "Survey" })).toBeNull();
  });

  it("imports a good file and applies it; refuses a bad one, applying nothing", async () => {
    const onApply = setup();
    const other: NamedLayout = { panel: "plan", layout: { beside: ["map", "monitor"], stacked: true, sizes: [0.4, 0.3, 0.3], height: 500 } };
    await importFile(layoutFile("Night", "scientist", other));
    expect(onApply).toHaveBeenCalledWith(other);
    expect((screen.getByLabelText("Named layout") as HTMLSelectElement).value).toBe("Night");
    onApply.mockClear();
    await importFile(JSON.stringify({ format: "modd-dock-layout", version: 1, name: "X", panel: "radar", layout: {} }), "bad.json");
    expect(screen.getByRole("alert").textContent).toBe("bad.json not imported: `panel` is \"radar\", not a panel (plan, monitor, map).");
    expect(onApply).not.toHaveBeenCalled();
    expect(screen.queryByRole("option", { name: "X" })).toBeNull();
  });
});
