/**
 * Tells the Downloads panel's reader that a credential file of the base
 * station was made anew with a new secret (deleted by hand, re-created at the
 * next start): copies handed out before, in stubs downloaded then among them,
 * no longer work; the log says it too (modd up, the SubBroker).
 */
import { useEffect, useState } from "react";
import { useServices } from "../../app/services";
import type { CredentialsRemade } from "../../api/types";

const WHAT: Record<string, string> = {
  "viewer.cred": "the scientists' viewer credential (their subscriber stubs name it)",
  "backend.cred": "the workbench's own credential",
  "subbroker.cred": "the SubBroker's credential",
  "deploy.key": "the deploy key",
};

export function RemadeCredentials() {
  const { api } = useServices();
  const [notes, setNotes] = useState<CredentialsRemade["remade"]>([]);
  useEffect(() => {
    let live = true;
    api.credentialsRemade().then((r) => { if (live) setNotes(r.remade); }, () => undefined); // an older backend: nothing to say
    return () => { live = false; };
  }, [api]);
  if (!notes.length) return null;
  return (
    <div className="error" role="alert" data-testid="credentials-remade">
      <strong>Credentials made anew:</strong>
      <ul>
        {notes.map((n) => (
          <li key={n.file}><code>{n.file}</code> ({WHAT[n.file] ?? "a credential"}) was missing and was made anew with a new secret at {n.at.replace("T", " ")}.</li>
        ))}
      </ul>
      Copies handed out before no longer work: download again and hand out the new ones.
    </div>
  );
}
