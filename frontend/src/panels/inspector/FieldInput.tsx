/**
 * One inspector field, chosen by the schema's input kind. Text-like inputs
 * commit on Enter or blur (a half-typed name is not applied); selects and
 * checkboxes commit at once. An emptied optional field is removed.
 */
import { useEffect, useId, useState } from "react";
import type { FieldSpec } from "../../core/schemaForm";
import type { TopicRef } from "../../core/query";
import { canonicalDecimal } from "../../core/canonical";

interface Props {
  spec: FieldSpec;
  value: unknown;
  topics: TopicRef[];
  readOnly: boolean;
  errors: string[];
  onCommit: (value: unknown) => void;
}

function toText(v: unknown): string {
  return v === undefined || v === null ? "" : String(v);
}

/** What a field stores for the text typed in it (the inspector's one conversion). */
export function parseField(spec: FieldSpec, text: string): unknown {
  if (text === "") return spec.required ? "" : undefined;
  if (spec.input === "integer" || spec.input === "number") {
    const n = Number(text);
    return Number.isFinite(n) ? n : text;
  }
  // One spelling of a decimal (the .modd parser's): "5" is stored as "5.0".
  if (spec.input === "decimal") return canonicalDecimal(text) ?? text;
  return text;
}

export function FieldInput({ spec, value, topics, readOnly, errors, onCommit }: Props) {
  const id = useId();
  const [text, setText] = useState(toText(value));
  useEffect(() => setText(toText(value)), [value]);
  const commit = () => { if (text !== toText(value)) onCommit(parseField(spec, text)); };
  const describedBy = `${id}-help`;
  const invalid = errors.length > 0;
  let control;
  switch (spec.input) {
    case "enum":
      control = (
        <select id={id} value={toText(value ?? spec.default)} disabled={readOnly} aria-invalid={invalid} aria-describedby={describedBy}
          onChange={(e) => onCommit(e.target.value === "" ? undefined : e.target.value)}>
          {!spec.required && <option value="">(default{spec.default !== undefined ? `: ${String(spec.default)}` : ""})</option>}
          {spec.options?.map((o) => <option key={o}>{o}</option>)}
        </select>
      );
      break;
    case "topic":
      control = (
        <select id={id} value={toText(value)} disabled={readOnly} aria-invalid={invalid} aria-describedby={describedBy}
          onChange={(e) => onCommit(e.target.value)}>
          <option value="">(choose a topic)</option>
          {topics.map((t) => <option key={t.id} value={t.name}>{t.name}</option>)}
        </select>
      );
      break;
    case "topics": {
      const chosen = new Set(Array.isArray(value) ? (value as string[]) : []);
      control = (
        <fieldset id={id} className="topic-checks" aria-describedby={describedBy} disabled={readOnly}>
          {topics.length === 0 && <span className="muted">no measured variables yet</span>}
          {topics.map((t) => (
            <label key={t.id}>
              <input type="checkbox" checked={chosen.has(t.name)}
                onChange={(e) => onCommit(e.target.checked ? [...chosen, t.name] : [...chosen].filter((x) => x !== t.name))} />
              {t.name}
            </label>
          ))}
        </fieldset>
      );
      break;
    }
    default:
      control = (
        <>
          <input id={id} value={text} readOnly={readOnly} aria-invalid={invalid} aria-describedby={describedBy}
            list={spec.input === "enumOrText" ? `${id}-options` : undefined}
            inputMode={spec.input === "integer" || spec.input === "decimal" || spec.input === "number" ? "decimal" : undefined}
            placeholder={spec.default !== undefined ? String(spec.default) : undefined}
            onChange={(e) => setText(e.target.value)}
            onBlur={commit}
            onKeyDown={(e) => { if (e.key === "Enter") commit(); if (e.key === "Escape") setText(toText(value)); }} />
          {spec.input === "enumOrText" && (
            <datalist id={`${id}-options`}>{spec.options?.map((o) => <option key={o} value={o} />)}</datalist>
          )}
        </>
      );
  }
  return (
    <div className={`field${invalid ? " field-invalid" : ""}`} data-field={spec.path.join(".")}>
      <label htmlFor={id}>{spec.label}{spec.required && <span aria-hidden> *</span>}</label>
      {control}
      {errors.map((e) => <div key={e} className="field-error" role="alert">{e}</div>)}
      <div id={describedBy} className="field-help">{spec.description}</div>
    </div>
  );
}
