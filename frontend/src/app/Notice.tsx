/** Why the last edit was refused, until dismissed or the next edit. */
import { useEditor, useEditorStore } from "../editor/useEditor";

export function Notice() {
  const store = useEditorStore();
  const notice = useEditor((s) => s.wb.notice);
  if (!notice) return null;
  return (
    <div className="notice" role="alert">
      {notice}
      <button aria-label="Dismiss" onClick={() => store.dispatch({ type: "dismissNotice" })}>×</button>
    </div>
  );
}
