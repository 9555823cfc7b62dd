import { describe, expect, it } from "vitest";
import { documentOf, metadataErrors, valuesOf } from "./metadataForm";
import { datasetFile, filenameOf, notesOf } from "../../api/download";

describe("the Dataset metadata form", () => {
  it("locates a naming authority that is not reversed DNS, a bad e-mail and a bad URL", () => {
    expect(metadataErrors({ naming_authority: "modd", creator_email: "ana at example", infoUrl: "example.org" })).toEqual({
      naming_authority: "not reversed DNS (org.example)",
      creator_email: "not an e-mail address (name@example.org)",
      infoUrl: "not an http(s) URL",
    });
    expect(metadataErrors({
      naming_authority: "org.example.marine", creator_email: "ana@marine.example.org",
      "platform.vocabulary": "https://mmisw.org/ont/ioos/platform", title: "anything",
    })).toEqual({});
    expect(metadataErrors({ creator_email: "  " })).toEqual({}); // empty: left out, not wrong
  });

  it("makes a document of the filled fields only, keeping the QC tests and GTS marks the form does not show", () => {
    const qc = { "usv.ctd.t": { spike_test: { suspect_threshold: 1 } } };
    const gts = ["usv.ctd.t"];
    const doc = documentOf({
      title: " Bay survey ", creator_name: "", keywords: "ocean, ctd,", "platform.id": "usv01",
      "instruments.ctd.make": "Sea-Bird", "instruments.ctd.serial_number": "12", "instruments.gnss.model": "",
    }, { qc, gts_ingest: gts, creator_name: "old" });
    expect(doc).toEqual({
      title: "Bay survey", keywords: ["ocean", "ctd"], platform: { id: "usv01" },
      instruments: { ctd: { make: "Sea-Bird", serial_number: "12" } }, qc, gts_ingest: gts,
    });
    expect(valuesOf({ title: "T", gts_ingest: gts, qc })).toEqual({ title: "T" });
    expect(documentOf({}, {})).toEqual({}); // nothing invented
  });

  it("reads a saved document back into the same fields", () => {
    const doc = { title: "T", keywords: ["a", "b"], platform: { name: "Boat" }, instruments: { ctd: { model: "SBE 37" } } };
    const values = valuesOf(doc);
    expect(values).toEqual({ title: "T", keywords: "a, b", "platform.name": "Boat", "instruments.ctd.model": "SBE 37" });
    expect(documentOf(values, doc)).toEqual(doc);
  });
});

describe("a download named by the backend", () => {
  it("takes the name of Content-Disposition, the exact one first", () => {
    expect(filenameOf('attachment; filename="usv-dataset-20260921T141320Z-20260921T151320Z.nc"'))
      .toBe("usv-dataset-20260921T141320Z-20260921T151320Z.nc");
    expect(filenameOf("attachment; filename=\"a_b.csv\"; filename*=UTF-8''a%22b-temp%C3%A9.csv")).toBe('a"b-tempé.csv');
    expect(filenameOf('attachment; filename="../../etc/passwd"')).toBe("passwd");
    expect(filenameOf(null)).toBeNull();
    expect(filenameOf("attachment")).toBeNull();
  });

  it("reads the export's notes, none when the header is absent or not a list", () => {
    expect(notesOf('["3 glitches dropped", 4]')).toEqual(["3 glitches dropped"]);
    expect(notesOf("not json")).toEqual([]);
    expect(notesOf(null)).toEqual([]);
    const headers = new Headers({ "X-Modd-Notes": '["n"]' });
    expect(datasetFile(new Blob(["x"]), headers, "usv-dataset")).toMatchObject({ name: "usv-dataset", notes: ["n"] });
  });
});
