import { describe, expect, it } from "vitest";
import { datasetRequest, exportables, type ExportChoice } from "./exportForm";
import type { ArchiveFile } from "../../api/types";
import type { ModdModel } from "../../core/model.gen";

const model = { drone: { name: "usv", sensors: [] } } as unknown as ModdModel;
const file: ArchiveFile = { name: "usv-0000.mcap", size: 1, complete: true, start_ns: 1_000_000_000_000, end_ns: null, topics: [] };
const choice: ExportChoice = { format: "netcdf", from: "", to: "", topics: [], resample: "" };

describe("the Export dataset form", () => {
  it("asks for the file's range in ns, every topic when none is chosen", () => {
    expect(datasetRequest(model, { ...choice, from: "1.5", to: "10" }, file)).toEqual({
      model, format: "netcdf", files: ["usv-0000.mcap"], start_ns: 1_001_500_000_000, end_ns: 1_010_000_000_000,
      topics: null, resample_s: null,
    });
    expect(datasetRequest(model, { ...choice, topics: ["usv.a.x"], resample: "2" }, null)).toMatchObject({
      files: [], start_ns: null, topics: ["usv.a.x"], resample_s: 2,
    });
  });

  it("says which field it cannot read", () => {
    expect(datasetRequest(model, { ...choice, from: "soon" }, file)).toBe("from: a number of seconds, please");
    expect(datasetRequest(model, { ...choice, resample: "0" }, file)).toBe("resample: a period greater than zero");
  });

  it("asks for the windows the subscribers received from every record, by subscriber", () => {
    const withSubs = { ...model, subscribers: [{ name: "sub_1" }, { name: "track_lat" }] } as unknown as ModdModel;
    expect(datasetRequest(withSubs, { ...choice, source: "received", from: "2", topics: ["sub_1"] }, file)).toEqual({
      model: withSubs, format: "netcdf", source: "received", files: [], start_ns: 1_002_000_000_000, end_ns: null,
      topics: ["sub_1"], resample_s: null,
    });
    expect(exportables(withSubs, file, "received")).toEqual(["sub_1", "track_lat"]);
    expect(exportables(withSubs, { ...file, topics: [{ topic: "usv.a.x", messages: 3 }] }, "archive")).toEqual(["usv.a.x"]);
  });

  it("names the project whose saved metadata the file carries", () => {
    expect(datasetRequest(model, choice, file, 7)).toMatchObject({ project: 7 });
    expect(datasetRequest(model, choice, file)).not.toHaveProperty("project");
  });
});
