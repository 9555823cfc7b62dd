/**
 * Which archive the live plan is calibrated by (docs/planning.md, "Bounds and
 * estimates"): the archives the backend holds for the model's drone (a test
 * flight), or none (quantised values sized at their declared range). The
 * choice is the store's `plan.calibrate`, which useLivePlan sends with the
 * model. Without the backend's services (a panel shown alone) it is hidden;
 * with them it is shown even before the drone has an archive. The list is read
 * again when the picker gets the focus: a test flight's archive that reaches
 * the backend while the panel is open can be chosen.
 */
import { useContext, useEffect, useState } from "react";
import { ServicesContext } from "../../app/services";
import { useEditor, useEditorStore } from "../../editor/useEditor";

/** The archive names of `drone`, [] until they are read or when they cannot be; and a
 * function that reads them again (a listing reads each file's summary: not polled). */
function useArchiveNames(drone: string): [string[], () => void, boolean] {
  const services = useContext(ServicesContext);
  const [names, setNames] = useState<string[]>([]);
  const [reads, setReads] = useState(0);
  useEffect(() => {
    let live = true;
    services?.api.listArchives(drone)
      .then((files) => { if (live) setNames(files.map((f) => f.name)); })
      .catch(() => { if (live) setNames([]); });
    return () => { live = false; };
  }, [services, drone, reads]);
  return [names, () => setReads((n) => n + 1), services !== null];
}

export function CalibrationPicker({ drone }: { drone: string }) {
  const store = useEditorStore();
  const chosen = useEditor((s) => s.plan.calibrate) ?? "";
  const [names, reread, served] = useArchiveNames(drone);
  if (!served) return null;
  const choose = (value: string) => store.patch((s) => ({ plan: { ...s.plan, calibrate: value || null } }));
  return (
    <label className="calibration" title="Size quantised values from a test flight's archive instead of the declared ranges">
      Calibrate by{" "}
      <select aria-label="Calibrate by archive" value={chosen} onFocus={reread} onChange={(e) => choose(e.target.value)}>
        <option value="">no archive (declared ranges)</option>
        {names.length === 0 && <option value="" disabled>{`no archive of ${drone} yet`}</option>}
        {names.map((n) => <option key={n} value={`${drone}/${n}`}>{n}</option>)}
      </select>
    </label>
  );
}
