/**
 * Units offered where a person types one (the New sensor form): the schema's
 * examples, UDUNITS-2 strings as CF writes them ("m s-2", "degC"), each with the
 * symbol people read ("m/s²", "°C") so that typing either finds it. The
 * schema's list is the one home; the symbols are only labels.
 *
 * @example unitChoices().find((u) => u.value === "m s-2")?.label // "m/s² (m s-2)"
 */
import { MODD_SCHEMA } from "./schema";

const SYMBOLS: Readonly<Record<string, string>> = {
  "m s-2": "m/s²", "m s-1": "m/s", degC: "°C", "rad s-1": "rad/s", "1": "no unit (1)",
  degree_north: "° north (latitude)", degree_east: "° east (longitude)", degree: "°", percent: "%",
  "S m-1": "S/m", "ug L-1": "µg/L", "mg m-3": "mg/m³", "umol kg-1": "µmol/kg",
};

export interface UnitChoice { value: string; label: string }

export function unitChoices(): UnitChoice[] {
  const examples = (MODD_SCHEMA.$defs?.Unit?.examples ?? []).filter((u) => u !== "m/s²");
  return examples.map((value) => ({ value, label: SYMBOLS[value] ? `${SYMBOLS[value]} (${value})` : value }));
}
