import { describe, expect, it } from "vitest";
import { checkField, formFor, kindDescription, type FieldSpec } from "./schemaForm";
import { MODD_SCHEMA } from "./schema";
import { KnownUnitValues, AggregationValues } from "./model.gen";

const paths = (kind: Parameters<typeof formFor>[1]) => formFor(MODD_SCHEMA, kind).map((f) => f.path.join("."));
const field = (kind: Parameters<typeof formFor>[1], path: string): FieldSpec =>
  formFor(MODD_SCHEMA, kind).find((f) => f.path.join(".") === path)!;

describe("forms from the schema", () => {
  it("lists each kind's fields in schema order, objects flattened, arrays of objects left out", () => {
    expect(paths("subscriber")).toEqual(["name", "endpoint.host", "endpoint.port", "topic", "periodS", "aggregation", "percentile", "deadband", "deadbandPercent",
      "level", "hysteresis", "crossing", "maxEvents", "alert", "resolution", "backfill"]);
    expect(paths("publisher")).toEqual(["name", "endpoint.host", "endpoint.port", "periodS", "topics"]);
    expect(paths("drone")).toEqual(["name", "description", "position.latitude", "position.longitude",
      "position.altitude", "position.maxGapS"]);
    // The schema grows (e.g. MAVLink sensors): new properties appear, arrays of objects stay out.
    expect(paths("sensor").slice(0, 2)).toEqual(["name", "description"]);
    expect(paths("sensor")).not.toContain("variables");
    expect(paths("topic").slice(0, 4)).toEqual(["name", "unit", "type", "description"]);
    expect(paths("pubBroker")).toEqual(["name", "endpoint.host", "endpoint.port", "logPath", "ingress.unixSocket", "ingress.tcpPort"]);
    expect(paths("link")).toContain("pingS");
  });

  it("takes inputs, options and help from the schema", () => {
    expect(field("subscriber", "aggregation")).toMatchObject({ input: "enum", options: [...AggregationValues], required: true });
    expect(field("subscriber", "aggregation").description).toMatch(/reduced/);
    // Units are offered as the symbols people type (UDUNITS), never as the paper's enum names.
    const unit = field("topic", "unit");
    expect(unit.input).toBe("enumOrText");
    expect(unit.options).toEqual(expect.arrayContaining(["m s-2", "degC", "degree_north", "m/s²"]));
    expect(unit.options?.filter((o) => (KnownUnitValues as readonly string[]).includes(o))).toEqual([]);
    expect(field("subscriber", "topic").input).toBe("topic");
    expect(field("subscriber", "alert")).toMatchObject({ input: "choices", options: ["designer", "integrator", "scientist", "operator"] });
    expect(checkField(field("subscriber", "alert"), ["scientist", "operator"])).toBeNull();
    expect(checkField(field("subscriber", "alert"), ["pilot"])).toMatch(/some of designer/);
    expect(field("publisher", "topics")).toMatchObject({ input: "topics", minItems: 1 });
    expect(field("subscriber", "periodS").input).toBe("decimal");
    expect(field("pubBroker", "endpoint.port")).toMatchObject({ input: "integer", minimum: 1, maximum: 65535, required: true });
    // An optional object's fields are optional.
    expect(field("subscriber", "endpoint.port").required).toBe(false);
    expect(field("link", "maxBuffer").default).toBe(1000);
    expect(kindDescription(MODD_SCHEMA, "subscriber")).toMatch(/consumer/);
  });

  it("checks values", () => {
    expect(checkField(field("subscriber", "periodS"), "0.25")).toBeNull();
    expect(checkField(field("subscriber", "periodS"), ".25")).toMatch(/decimal/);
    expect(checkField(field("subscriber", "periodS"), "")).toBe("required");
    expect(checkField(field("subscriber", "topic"), "")).toBe("required");
    expect(checkField(field("subscriber", "topic"), "a.b")).toMatch(/topic/);
    expect(checkField(field("subscriber", "name"), "9x")).toMatch(/letter/);
    expect(checkField(field("pubBroker", "endpoint.port"), 70000)).toMatch(/at most/);
    expect(checkField(field("pubBroker", "endpoint.port"), 1.5)).toMatch(/whole/);
    expect(checkField(field("subscriber", "aggregation"), "MODE")).toMatch(/one of/);
    expect(checkField(field("publisher", "topics"), [])).toMatch(/no topic/);
    expect(checkField(field("subscriber", "endpoint.host"), undefined)).toBeNull();
  });
});
