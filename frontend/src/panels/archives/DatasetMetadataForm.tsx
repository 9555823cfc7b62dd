/**
 * Archives → Dataset metadata: what a data centre asks of a dataset (ACDD 1.3,
 * IOOS 1.2: title, creator, publisher, license, naming authority, platform,
 * each sensor's instrument...), filled by the scientist and saved with the
 * project as a new revision (GET/PUT /api/projects/{id}/dataset-metadata).
 * Every export then carries it. A fault is shown beside its field (the
 * browser's checks first, then the backend's, located by key).
 */
import { useEffect, useState } from "react";
import { useServices } from "../../app/services";
import { ApiError } from "../../api/http";
import type { DatasetMetadata } from "../../api/types";
import type { ModdModel } from "../../core/model.gen";
import { INSTRUMENT_FIELDS, METADATA_FIELDS, documentOf, metadataErrors, valuesOf, type MetadataValues } from "./metadataForm";

interface FieldProps { id: string; label: string; hint?: string; long?: boolean; value: string; error?: string; onChange: (v: string) => void }

function Field({ id, label, hint, long, value, error, onChange }: FieldProps) {
  const common = {
    id, value, "aria-label": label, "aria-invalid": error ? true : undefined,
    "aria-describedby": error ? `${id}-error` : undefined, placeholder: hint ?? "",
  };
  return (
    <label className="metadata-field">
      <span>{label}</span>
      {long ? <textarea rows={2} {...common} onChange={(e) => onChange(e.target.value)} />
        : <input {...common} onChange={(e) => onChange(e.target.value)} />}
      {error && <span id={`${id}-error`} className="error" role="alert">{label}: {error}</span>}
    </label>
  );
}

export function DatasetMetadataForm({ model, project }: { model: ModdModel; project: number }) {
  const { api } = useServices();
  const [saved, setSaved] = useState<DatasetMetadata | null>(null);
  const [values, setValues] = useState<MetadataValues>({});
  const [errors, setErrors] = useState<Record<string, string>>({});
  const [state, setState] = useState<{ busy?: boolean; error?: string; done?: string }>({});
  useEffect(() => {
    let live = true;
    api.readDatasetMetadata(project).then((m) => {
      if (live) { setSaved(m); setValues(valuesOf(m.metadata)); }
    }, (err: Error) => live && setState({ error: err.message }));
    return () => { live = false; };
  }, [api, project]);

  const save = async (e: React.FormEvent) => {
    e.preventDefault();
    if (!saved) return;
    const found = metadataErrors(values);
    setErrors(found);
    if (Object.keys(found).length) { setState({ error: "fix the fields marked" }); return; }
    setState({ busy: true });
    try {
      const next = await api.saveDatasetMetadata(project, documentOf(values, saved.metadata), saved.revision);
      setSaved(next); setValues(valuesOf(next.metadata));
      setState({ done: `Saved revision ${next.revision}` });
    } catch (err) {
      const key = err instanceof ApiError ? (err.body as { key?: unknown }).key : undefined;
      if (typeof key === "string") setErrors({ [key]: (err as Error).message });
      setState({ error: (err as Error).message });
    }
  };
  const set = (key: string) => (v: string) => setValues({ ...values, [key]: v });
  const sensors = model.drone.sensors.map((s) => s.name);
  const fieldOf = (key: string, label: string, hint?: string, long?: boolean) => (
    <Field key={key} id={`dm-${key.replace(/\W/g, "-")}`} label={label} hint={hint} long={long}
      value={values[key] ?? ""} error={errors[key]} onChange={set(key)} />
  );

  return (
    <details className="archive-form dataset-metadata">
      <summary>Dataset metadata{saved ? ` (revision ${saved.revision})` : ""}</summary>
      <form onSubmit={save} aria-label="Dataset metadata">
        <div className="metadata-grid">
          {METADATA_FIELDS.map((f) => fieldOf(f.key, f.label, f.hint, f.kind === "long"))}
          {sensors.map((s) => INSTRUMENT_FIELDS.map((f) => fieldOf(`instruments.${s}.${f.field}`, `Instrument ${s} ${f.label}`)))}
        </div>
        {saved && saved.missing.length > 0 && (
          <p className="muted" aria-label="Asked for by data centres">
            Not given yet (ACDD 1.3 / IOOS 1.2 ask for them): {saved.missing.join(", ")}
          </p>
        )}
        <button type="submit" disabled={!saved || state.busy}>Save metadata</button>
        {state.done && <span role="status">{state.done}</span>}
        {state.error && <span className="error" role="alert">{state.error}</span>}
      </form>
    </details>
  );
}
