/** "Alert sound" on or off for this browser (off by default; app/useAlerts). */
import { useState } from "react";
import { setSound, soundOn } from "./useAlerts";

export function SoundToggle({ onChange }: { onChange?: (on: boolean) => void }) {
  const [on, setOn] = useState(soundOn());
  return (
    <label className="sound-toggle">
      <input type="checkbox" checked={on} onChange={(e) => { setSound(e.target.checked); setOn(e.target.checked); onChange?.(e.target.checked); }} />
      {" "}Alert sound
    </label>
  );
}
