/**
 * The Dataset metadata form's rules, apart from the component: the fields
 * (ACDD 1.3 / IOOS 1.2 attribute names, the platform's, each sensor's
 * instrument), a document from the filled form and back, and the same checks
 * as the backend's (modd.dataset.metadata), located by key.
 *
 *   metadataErrors({ naming_authority: "modd" })
 *   // { naming_authority: "not reversed DNS (org.example)" }
 *
 * Nothing is invented: an empty field is left out of the document (the
 * export's notes then name what a data centre asks for).
 */
import type { DatasetMetadataDoc } from "../../api/types";

export type FieldKind = "text" | "long" | "email" | "url" | "dns" | "list";

export interface MetadataField {
  key: string; // the document's key; "platform.id" for the platform's
  label: string;
  kind: FieldKind;
  hint?: string;
}

export const METADATA_FIELDS: MetadataField[] = [
  { key: "title", label: "Title", kind: "text" },
  { key: "summary", label: "Summary", kind: "long" },
  { key: "keywords", label: "Keywords", kind: "list", hint: "comma-separated" },
  { key: "keywords_vocabulary", label: "Keywords vocabulary", kind: "text", hint: "e.g. GCMD Science Keywords" },
  { key: "creator_name", label: "Creator name", kind: "text" },
  { key: "creator_email", label: "Creator e-mail", kind: "email" },
  { key: "creator_url", label: "Creator URL", kind: "url" },
  { key: "creator_institution", label: "Creator institution", kind: "text" },
  { key: "publisher_name", label: "Publisher name", kind: "text" },
  { key: "publisher_email", label: "Publisher e-mail", kind: "email" },
  { key: "publisher_url", label: "Publisher URL", kind: "url" },
  { key: "institution", label: "Institution", kind: "text" },
  { key: "license", label: "License", kind: "text", hint: "e.g. CC-BY-4.0" },
  { key: "project", label: "Project", kind: "text" },
  { key: "acknowledgement", label: "Acknowledgement", kind: "long" },
  { key: "naming_authority", label: "Naming authority", kind: "dns", hint: "reversed DNS, e.g. org.example.marine" },
  { key: "infoUrl", label: "Information URL", kind: "url" },
  { key: "contributor_name", label: "Contributor name", kind: "text" },
  { key: "contributor_role", label: "Contributor role", kind: "text", hint: "e.g. principalInvestigator" },
  { key: "platform.name", label: "Platform name", kind: "text" },
  { key: "platform.id", label: "Platform id", kind: "text" },
  { key: "platform.type", label: "Platform type", kind: "text", hint: "e.g. surface_vehicle" },
  { key: "platform.vocabulary", label: "Platform vocabulary", kind: "url", hint: "e.g. https://mmisw.org/ont/ioos/platform" },
  { key: "instrument_vocabulary", label: "Instrument vocabulary", kind: "url", hint: "e.g. https://vocab.nerc.ac.uk/collection/L22/current/" },
];

/** Each sensor's instrument fields: `instruments.<sensor>.<field>`. */
export const INSTRUMENT_FIELDS = [
  { field: "make", label: "make" },
  { field: "model", label: "model" },
  { field: "serial_number", label: "serial number" },
] as const;

/** The form's values: one text per key (`platform.id`, `instruments.ctd.make`). */
export type MetadataValues = Record<string, string>;

const DNS = /^[a-z0-9-]+(\.[a-z0-9-]+)+$/i;
const EMAIL = /^[^@\s,]+@[^@\s,]+\.[^@\s,.]+$/;
const URL_FORM = /^https?:\/\/[^\s/]+(\.[^\s]*|)$/i;

function text(v: unknown): string {
  if (Array.isArray(v)) return v.map(String).join(", ");
  return v === undefined || v === null ? "" : String(v);
}

/** The form's values of a saved document. */
export function valuesOf(doc: DatasetMetadataDoc): MetadataValues {
  const out: MetadataValues = {};
  for (const [k, v] of Object.entries(doc)) {
    if (k === "platform" || k === "instruments" || KEPT.includes(k)) continue;
    out[k] = text(v);
  }
  const platform = (doc.platform ?? {}) as Record<string, unknown>;
  for (const [k, v] of Object.entries(platform)) out[`platform.${k}`] = text(v);
  const instruments = (doc.instruments ?? {}) as Record<string, Record<string, unknown>>;
  for (const [sensor, inst] of Object.entries(instruments)) {
    for (const [k, v] of Object.entries(inst ?? {})) out[`instruments.${sensor}.${k}`] = text(v);
  }
  return out;
}

/** The document's sections the form does not show, kept as saved: the QARTOD tests and
 * the variables sent to NDBC/GTS (docs/user-guide/datasets.md). */
const KEPT = ["qc", "gts_ingest"];

/** The document of the filled form: empty fields left out, what the form does not show (`KEPT`) kept. */
export function documentOf(values: MetadataValues, saved: DatasetMetadataDoc): DatasetMetadataDoc {
  const doc: DatasetMetadataDoc = {};
  for (const k of KEPT) if (saved[k] !== undefined) doc[k] = saved[k];
  const platform: Record<string, string> = {};
  const instruments: Record<string, Record<string, string>> = {};
  for (const [key, raw] of Object.entries(values)) {
    const v = raw.trim();
    if (!v) continue;
    const parts = key.split(".");
    if (parts[0] === "platform" && parts.length === 2) platform[parts[1]] = v;
    else if (parts[0] === "instruments" && parts.length >= 3) {
      const field = parts[parts.length - 1], sensor = parts.slice(1, -1).join(".");
      (instruments[sensor] ??= {})[field] = v;
    } else if (key === "keywords") doc.keywords = v.split(",").map((w) => w.trim()).filter(Boolean);
    else doc[key] = v;
  }
  if (Object.keys(platform).length) doc.platform = platform;
  if (Object.keys(instruments).length) doc.instruments = instruments;
  return doc;
}

function kindOf(key: string): FieldKind {
  return METADATA_FIELDS.find((f) => f.key === key)?.kind ?? "text";
}

/** What is wrong with each filled field, by key (none: ready to save). */
export function metadataErrors(values: MetadataValues): Record<string, string> {
  const errors: Record<string, string> = {};
  for (const [key, raw] of Object.entries(values)) {
    const v = raw.trim();
    if (!v) continue;
    const kind = kindOf(key);
    if (kind === "dns" && !DNS.test(v)) errors[key] = "not reversed DNS (org.example)";
    if (kind === "email" && !v.split(",").every((e) => EMAIL.test(e.trim()))) {
      errors[key] = "not an e-mail address (name@example.org)";
    }
    if (kind === "url" && !URL_FORM.test(v)) errors[key] = "not an http(s) URL";
  }
  return errors;
}
