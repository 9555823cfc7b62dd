/**
 * The layout menu's named layouts (core/namedLayouts.ts): save the current
 * arrangement under a name, switch to one, delete it, export it as a JSON
 * file and import one (refused with its located error, nothing applied).
 * Kept in this browser per user and role.
 */
import { useState } from "react";
import { deleteNamed, layoutFile, layoutFileName, listNamed, MAX_FILE_BYTES, MAX_NAME, parseLayoutFile, saveNamed, type NamedLayout } from "../core/namedLayouts";
import { saveBlob } from "../panels/saveBlob";

interface Props {
  user: string;
  role: string;
  panels: readonly string[];
  current: NamedLayout;
  onApply: (named: NamedLayout) => void;
  /** The storage (localStorage in the app). */
  store?: Storage;
}

export function NamedLayouts({ user, role, panels, current, onApply, store = window.localStorage }: Props) {
  const [chosen, setChosen] = useState("");
  const [name, setName] = useState("");
  const [message, setMessage] = useState<{ error: boolean; text: string } | null>(null);
  const all = listNamed(store, user, role, panels);
  const names = Object.keys(all).sort((a, b) => a.localeCompare(b));
  const said = (error: boolean, text: string) => { setMessage({ error, text }); };

  const save = () => {
    const problem = saveNamed(store, user, role, name, current, panels);
    if (problem) { said(true, problem); return; }
    setChosen(name.trim());
    said(false, `Saved “${name.trim()}”.`);
  };
  const pick = (n: string) => { setChosen(n); if (all[n]) { onApply(all[n]); said(false, `Switched to “${n}”.`); } };
  const remove = () => { deleteNamed(store, user, role, chosen, panels); said(false, `Deleted “${chosen}”.`); setChosen(""); };
  const exportIt = () => {
    const n = chosen || "Current";
    saveBlob(new Blob([layoutFile(n, role, all[chosen] ?? current)], { type: "application/json" }), layoutFileName(n));
  };
  const importIt = async (file: File | undefined) => {
    if (!file) return;
    if (file.size > MAX_FILE_BYTES) { said(true, `${file.name}: ${file.size} bytes; a layout file has at most ${MAX_FILE_BYTES}`); return; }
    const read = parseLayoutFile(await file.text(), panels);
    if ("error" in read) { said(true, `${file.name} not imported: ${read.error}.`); return; }
    const problem = saveNamed(store, user, role, read.name, read.named, panels);
    if (problem) { said(true, `${file.name} not imported: ${problem}.`); return; }
    setChosen(read.name);
    onApply(read.named);
    said(false, `Imported “${read.name}” and switched to it.`);
  };

  return (
    <fieldset className="named-layouts" aria-label="Named layouts">
      <legend>Named layouts</legend>
      <label>Layout{" "}
        <select aria-label="Named layout" value={chosen} onChange={(e) => pick(e.target.value)}>
          <option value="">(this one, unnamed)</option>
          {names.map((n) => <option key={n} value={n}>{n}</option>)}
        </select>
      </label>
      <div className="named-layouts-row">
        <input aria-label="Layout name" placeholder="Name" maxLength={MAX_NAME + 10} value={name} onChange={(e) => setName(e.target.value)} />
        <button type="button" onClick={save}>Save as</button>
      </div>
      <div className="named-layouts-row">
        <button type="button" onClick={remove} disabled={!chosen}>Delete</button>
        <button type="button" onClick={exportIt}>Export…</button>
        <label className="button-like">Import…
          <input type="file" accept=".json,application/json" aria-label="Import layout file" hidden
            onChange={(e) => { void importIt(e.target.files?.[0]); e.target.value = ""; }} />
        </label>
      </div>
      {message && <p className={message.error ? "error" : "muted"} role={message.error ? "alert" : "status"} data-testid="layout-message">{message.text}</p>}
    </fieldset>
  );
}
