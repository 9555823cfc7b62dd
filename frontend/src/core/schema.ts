/**
 * The metamodel's JSON Schema, imported at build time from
 * metamodel/modd.schema.json (the `@schema` alias in vite.config.ts and
 * tsconfig.json): the inspector reads it, no copy is kept.
 */
import raw from "@schema/modd.schema.json";
import type { JsonSchema } from "./schemaForm";

export const MODD_SCHEMA: JsonSchema = raw as JsonSchema;
