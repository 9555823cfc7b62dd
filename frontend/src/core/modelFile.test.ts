import { describe, expect, it } from "vitest";
import { decodeModelBytes, modelFile } from "./modelFile";

describe("modelFile", () => {
  it("reads UTF-8 and drops a byte-order mark", () => {
    const bytes = new Uint8Array([0xef, 0xbb, 0xbf, ...new TextEncoder().encode("// é\nDrone")]);
    expect(decodeModelBytes(bytes)).toEqual({ text: "// é\nDrone", encoding: "utf-8" });
  });

  it("reads bytes that are not UTF-8 as windows-1252", () => {
    // "temp\xe9rature \x96 25 \xb0C" in windows-1252: é, en dash, degree sign
    const bytes = new Uint8Array([0x74, 0x65, 0x6d, 0x70, 0xe9, 0x20, 0x96, 0x20, 0xb0, 0x43]);
    expect(decodeModelBytes(bytes)).toEqual({ text: "tempé – °C", encoding: "windows-1252" });
  });

  it("takes the notation and the project name from the file name", () => {
    const none = new Uint8Array();
    expect(modelFile("mission.collector", none)).toMatchObject({ name: "mission", format: "modd" });
    expect(modelFile("Mission.JSON", none)).toMatchObject({ name: "Mission", format: "json" });
    expect(modelFile("boat (copy).modd", none)).toMatchObject({ name: "boat _copy_", format: "modd" });
    expect(modelFile("..collector", none).name).toBe("imported");
  });
});
