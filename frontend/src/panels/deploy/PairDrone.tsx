/**
 * Pairing a drone with this base station (docs/operations.md, "Pair"): the
 * operator makes the bundle for the project's drone — saved as a file to carry
 * on a USB stick — and reads its one-time code here, once (it is kept in this
 * component's state only: never stored, never in a URL). On the drone:
 * `sudo modd-pair <drone>.modd-pair`, then type the code.
 */
import { useState } from "react";
import { useServices } from "../../app/services";
import type { Pairing } from "../../api/types";
import { saveBlob } from "../saveBlob";

export function PairDrone({ projectId, revision, allowed }: { projectId: number; revision: number; allowed: boolean }) {
  const { api } = useServices();
  const [made, setMade] = useState<Pairing | null>(null);
  const [state, setState] = useState<{ busy: boolean; error: string | null }>({ busy: false, error: null });

  const make = async () => {
    setState({ busy: true, error: null });
    setMade(null);
    try {
      const p = await api.makePairing(projectId, revision);
      saveBlob(new Blob([p.bundle], { type: "application/octet-stream" }), p.filename);
      setMade(p);
      setState({ busy: false, error: null });
    } catch (e) {
      setState({ busy: false, error: (e as Error).message });
    }
  };

  return (
    <section aria-label="Pair a drone" className="pair-drone">
      <h3>Pair the drone</h3>
      <p className="muted">
        A signed bundle with the drone&apos;s configuration and link key, encrypted with a one-time code.
        Carry the file to the drone and run <code>sudo modd-pair FILE</code> there.
      </p>
      <button onClick={() => void make()} disabled={!allowed || state.busy || revision === 0}>
        {state.busy ? "Making the bundle…" : `Make the pairing bundle (revision ${revision})`}
      </button>
      {!allowed && <span className="muted"> Only the operator pairs drones.</span>}
      {state.error && <span className="error" role="alert" data-testid="pairing-error"> {state.error}</span>}
      {made && (
        <div className="pairing-made" data-testid="pairing-made">
          <p role="status">Saved <code>{made.filename}</code> for drone <strong>{made.drone}</strong> (valid until{" "}
            {new Date(made.expires_at).toLocaleString(undefined, { dateStyle: "short", timeStyle: "short" })}).</p>
          <p>One-time code — shown once, type it on the drone:{" "}
            <code className="pairing-code" aria-label="Pairing code">{made.code}</code>
            {" "}<button className="link" onClick={() => setMade(null)}>Hide</button></p>
          <p className="muted">The drone pins this base station&apos;s key <code aria-label="Station fingerprint">{made.fingerprint}</code>.
            This station&apos;s SubBroker for {made.drone} reads the link key from <code>{made.link_key_file}</code>
            {" "}(<code>[link] key = &quot;file:{made.link_key_file}&quot;</code>).</p>
        </div>
      )}
    </section>
  );
}
