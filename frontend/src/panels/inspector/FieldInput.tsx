/**
 * One inspector field, chosen by the schema's input kind. Text-like inputs
 * apply as you type, once typing pauses (TYPING_DELAY_MS) and only a value
 * the field accepts (a half-typed "0." waits), and at once on Enter or blur;
 * selects and checkboxes commit at once. An emptied optional field is removed.
 * What you type stays as typed while the field has the focus, even when the
 * model spells it its own way ("5" is stored as "5.0") or renames the element.
 */
import { useEffect, useId, useRef, useState } from "react";
import { checkField, type FieldSpec } from "../../core/schemaForm";
import type { TopicRef } from "../../core/query";
import { topicRefLabel } from "../../core/topicLabel";
import { canonicalDecimal, sameMeaning } from "../../core/canonical";

/** Pause in typing after which the field is applied (the plan follows). */
export const TYPING_DELAY_MS = 400;

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
  const focused = useRef(false);
  // Out of focus the field shows the model's value: an edit the view refused (or undone) does not stay on screen.
  const [editing, setEditing] = useState(false);
  const timer = useRef<ReturnType<typeof setTimeout> | null>(null);
  const latest = useRef({ text, value, onCommit });
  latest.current = { text, value, onCommit };
  const shown = useRef(value);
  useEffect(() => {
    if (sameMeaning({ v: shown.current }, { v: value })) return; // a re-render, not a new value
    shown.current = value;
    // Keep the typed text while focused when it means the value (no jump from "5" to "5.0" mid-typing).
    setText((prev) => (focused.current && sameMeaning({ v: parseField(spec, prev) }, { v: value }) ? prev : toText(value)));
  }, [value, spec]);
  useEffect(() => () => { if (timer.current) clearTimeout(timer.current); }, []);
  const commitText = (t: string) => {
    if (timer.current) { clearTimeout(timer.current); timer.current = null; }
    const { value: v, onCommit: apply } = latest.current;
    const parsed = parseField(spec, t);
    if (t !== toText(v) && !sameMeaning({ v: parsed }, { v })) apply(parsed);
  };
  /** Enter or blur: applies now, and shows the value as stored ("5" → "5.0"). */
  const commit = () => {
    const t = latest.current.text;
    commitText(t);
    setText(toText(parseField(spec, t)));
  };
  const typed = (t: string) => {
    setText(t);
    if (timer.current) clearTimeout(timer.current);
    // As you type: only a value the field accepts (the whole form is checked again on blur/Enter).
    if (checkField(spec, parseField(spec, t)) === null) timer.current = setTimeout(() => commitText(t), TYPING_DELAY_MS);
  };
  const describedBy = `${id}-help`;
  const invalid = errors.length > 0;
  let control;
  switch (spec.input) {
    case "enum":
      control = (
        <select id={id} value={toText(value ?? spec.default)} disabled={readOnly} aria-invalid={invalid} aria-describedby={describedBy}
          onChange={(e) => onCommit(e.target.value === "" ? undefined : e.target.value)}>
          {!spec.required && <option value="">{spec.emptyLabel ?? `(default${spec.default !== undefined ? `: ${String(spec.default)}` : ""})`}</option>}
          {spec.options?.map((o) => <option key={o}>{o}</option>)}
        </select>
      );
      break;
    case "topic":
      control = (
        <select id={id} value={toText(value)} disabled={readOnly} aria-invalid={invalid} aria-describedby={describedBy}
          onChange={(e) => onCommit(e.target.value)}>
          <option value="">(choose a topic)</option>
          {topics.map((t) => <option key={t.id} value={t.name}>{topicRefLabel(t)}</option>)}
        </select>
      );
      break;
    case "topics": {
      const chosen = new Set(Array.isArray(value) ? (value as string[]) : []);
      control = (
        <fieldset id={id} className="topic-checks" aria-describedby={describedBy} disabled={readOnly}>
          {topics.length === 0 && <span className="muted">no measured variables yet</span>}
          <SensorChoices topics={topics} chosen={chosen} onCommit={onCommit} />
          {topics.map((t) => (
            <label key={t.id}>
              <input type="checkbox" checked={chosen.has(t.name)}
                onChange={(e) => onCommit(e.target.checked ? [...chosen, t.name] : [...chosen].filter((x) => x !== t.name))} />
              {topicRefLabel(t)}
            </label>
          ))}
        </fieldset>
      );
      break;
    }
    case "choices": {
      // Some of a closed list; none chosen removes the field (an alert with no role is no alert).
      const chosen = Array.isArray(value) ? (value as string[]) : [];
      const pick = (o: string, on: boolean) => {
        const next = spec.options?.filter((x) => (x === o ? on : chosen.includes(x))) ?? [];
        onCommit(next.length ? next : undefined);
      };
      control = (
        <fieldset id={id} className="topic-checks" aria-describedby={describedBy} aria-label={spec.label} aria-invalid={invalid} disabled={readOnly}>
          {spec.options?.map((o) => (
            <label key={o}><input type="checkbox" checked={chosen.includes(o)} onChange={(e) => pick(o, e.target.checked)} /> {o}</label>
          ))}
        </fieldset>
      );
      break;
    }
    default:
      control = (
        <>
          <input id={id} value={editing ? text : toText(value)} readOnly={readOnly} aria-invalid={invalid} aria-describedby={describedBy}
            list={spec.input === "enumOrText" ? `${id}-options` : undefined}
            inputMode={spec.input === "integer" || spec.input === "decimal" || spec.input === "number" ? "decimal" : undefined}
            placeholder={spec.default !== undefined ? String(spec.default) : undefined}
            onChange={(e) => typed(e.target.value)}
            onFocus={() => { focused.current = true; setEditing(true); setText(toText(value)); }}
            onBlur={() => { focused.current = false; setEditing(false); commit(); }}
            onKeyDown={(e) => { if (e.key === "Enter") commit(); if (e.key === "Escape") { if (timer.current) clearTimeout(timer.current); setText(toText(value)); } }} />
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

/** One choice per sensor: all of its topics at once (a publisher often takes every variable of a sensor). */
function SensorChoices({ topics, chosen, onCommit }: { topics: TopicRef[]; chosen: Set<string>; onCommit: (value: unknown) => void }) {
  const sensors = [...new Set(topics.map((t) => t.sensor.name))];
  const of = (sensor: string) => topics.filter((t) => t.sensor.name === sensor).map((t) => t.name);
  const all = sensors.filter((s) => of(s).length > 1 && of(s).some((n) => !chosen.has(n)));
  if (!all.length) return null;
  return (
    <div className="sensor-choices">
      {all.map((s) => (
        <button key={s} type="button" onClick={() => onCommit([...chosen, ...of(s).filter((n) => !chosen.has(n))])}>All of {s}</button>
      ))}
    </div>
  );
}
