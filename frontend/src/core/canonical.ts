/**
 * One canonical form of every value, so that comparing two models compares
 * what they mean, not how they were typed: decimals are spelt as the .modd
 * parser spells them (modd_model/numbers.py `canonical_decimal`: "5" →
 * "5.0", ".50" → "0.5", "4.0E-2" → "0.04"), and object keys are in one
 * order. The decimal fields are read from the metamodel's schema (every
 * property whose type is `$defs/Decimal` or `$defs/Period`).
 *
 * @example canonicalJson({ b: "5", a: 1 }, new Set(["b"])) // '{"a":1,"b":"5.0"}'
 */
import { MODD_SCHEMA } from "./schema";

const LITERAL = /^(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$/;
const MAX_DIGITS = 40;

/** The parser's spelling of a decimal literal, or null when `text` is not one. */
export function canonicalDecimal(text: string): string | null {
  if (!LITERAL.test(text)) return null;
  const [mantissa, expPart] = text.toLowerCase().split("e");
  const exp = expPart === undefined ? 0 : Number(expPart);
  if (!Number.isSafeInteger(exp) || Math.abs(exp) > MAX_DIGITS) return null;
  let [int, frac = ""] = mantissa.split(".");
  // Shift the point by the exponent, on the digits (never through a float).
  let digits = int + frac;
  let point = int.length + exp;
  if (point < 0) { digits = "0".repeat(-point) + digits; point = 0; }
  if (point > digits.length) digits = digits + "0".repeat(point - digits.length);
  int = digits.slice(0, point).replace(/^0+/, "") || "0";
  frac = digits.slice(point).replace(/0+$/, "") || "0";
  const out = `${int}.${frac}`;
  return out.length > MAX_DIGITS + 1 ? null : out;
}

interface SchemaNode { [k: string]: unknown }

/** Property names typed Decimal or Period anywhere in the schema. */
export function decimalFields(schema: SchemaNode = MODD_SCHEMA as unknown as SchemaNode): Set<string> {
  const out = new Set<string>();
  const walk = (node: unknown): void => {
    if (Array.isArray(node)) { node.forEach(walk); return; }
    if (!node || typeof node !== "object") return;
    const n = node as SchemaNode;
    const props = n.properties as Record<string, SchemaNode> | undefined;
    if (props) {
      for (const [name, p] of Object.entries(props)) {
        if (typeof p.$ref === "string" && /\/(Decimal|Period)$/.test(p.$ref)) out.add(name);
      }
    }
    Object.values(n).forEach(walk);
  };
  walk(schema);
  return out;
}

const DECIMALS = decimalFields();

/** A value with decimals in their canonical spelling and keys sorted (a new value; the input is not changed). */
export function canonicalValue(v: unknown, decimals: ReadonlySet<string> = DECIMALS, key = ""): unknown {
  if (typeof v === "string") return decimals.has(key) ? canonicalDecimal(v) ?? v : v;
  if (Array.isArray(v)) return v.map((x) => canonicalValue(x, decimals, ""));
  if (v && typeof v === "object") {
    const out: Record<string, unknown> = {};
    for (const k of Object.keys(v).sort()) {
      const x = (v as Record<string, unknown>)[k];
      if (x !== undefined) out[k] = canonicalValue(x, decimals, k);
    }
    return out;
  }
  return v;
}

/** JSON of the canonical value: equal strings ⇔ equal meaning. */
export function canonicalJson(v: unknown, decimals: ReadonlySet<string> = DECIMALS): string {
  return JSON.stringify(canonicalValue(v, decimals)) ?? "undefined";
}

/** Whether two values mean the same (decimal spelling and key order aside). */
export function sameMeaning(a: unknown, b: unknown): boolean {
  return canonicalJson(a) === canonicalJson(b);
}
