// @vitest-environment jsdom
import { describe, expect, it } from "vitest";
import { notAppliedWords, textFormat } from "./TextPanel";

describe("the Text panel's reading of pasted text", () => {
  it("reads a pasted JSON model as JSON and anything else as .modd (.collector included)", () => {
    expect(textFormat('  \n{"schemaVersion": "1.0"}')).toBe("json");
    expect(textFormat("Drone usv { }")).toBe("modd");
    expect(textFormat("// a comment\nDrone usv { }")).toBe("modd");
  });

  it("counts the errors of text not applied and says where, once each", () => {
    const errs = [1, 2, 3, 4, 5, 6].map((line) => ({ severity: "error", message: `bad ${line}`, line, col: 2 }));
    const words = notAppliedWords(errs as never);
    expect(words).toBe("Not applied: 6 errors, marked in the text (line 1:2, line 2:2, line 3:2, line 4:2, line 5:2, …).");
    expect(words).not.toMatch(/bad \d/); // the messages are the markers', not repeated here
    expect(notAppliedWords([{ severity: "error", message: "x", pointer: "/drone" }] as never)).toBe("Not applied: 1 error, marked in the text (/drone).");
  });
});
