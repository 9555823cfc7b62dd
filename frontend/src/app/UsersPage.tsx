/**
 * The admin's page for accounts (/users): create a user with roles, change
 * a user's roles, reset a password (which ends that user's sessions),
 * delete. The backend refuses to remove the last admin and says so.
 */
import { useCallback, useEffect, useState } from "react";
import type { User } from "../api/types";
import type { Role } from "../core/roles";
import { useServices } from "./services";
import "./collab.css";

const ROLES: Role[] = ["designer", "integrator", "scientist", "operator", "admin"];

export function UsersPage({ me, onBack }: { me: User; onBack: () => void }) {
  const { api } = useServices();
  const [users, setUsers] = useState<User[] | null>(null);
  const [note, setNote] = useState<{ ok: boolean; text: string } | null>(null);
  const [name, setName] = useState("");
  const [password, setPassword] = useState("");
  const [roles, setRoles] = useState<Role[]>(["scientist"]);
  const load = useCallback(() => { api.listUsers().then(setUsers, (e: Error) => setNote({ ok: false, text: e.message })); }, [api]);
  useEffect(load, [load]);
  const act = async (what: string, f: () => Promise<unknown>) => {
    try { await f(); setNote({ ok: true, text: what }); } catch (e) { setNote({ ok: false, text: `${what}: ${(e as Error).message}` }); }
    load();
  };
  const toggle = (list: Role[], r: Role, on: boolean) => (on ? [...list, r] : list.filter((x) => x !== r));

  return (
    <main className="projects users-page">
      <header className="projects-head"><h1>Users and roles</h1><span>{me.username}</span><button onClick={onBack}>Projects</button></header>
      {note && <p className={note.ok ? "status-ok" : "error"} role={note.ok ? "status" : "alert"}>{note.text}</p>}
      {users && (
        <table className="users" aria-label="Users">
          <thead><tr><th>User</th>{ROLES.map((r) => <th key={r}>{r}</th>)}<th></th></tr></thead>
          <tbody>
            {users.map((u) => (
              <tr key={u.id} data-user={u.username}>
                <td>{u.username}</td>
                {ROLES.map((r) => (
                  <td key={r}><input type="checkbox" aria-label={`${u.username} ${r}`} checked={u.roles.includes(r)}
                    onChange={(e) => {
                      const next = toggle(u.roles, r, e.target.checked);
                      setUsers((list) => list?.map((x) => (x.id === u.id ? { ...x, roles: next } : x)) ?? null); // shown at once; the reload corrects a refusal
                      void act(`${u.username}: roles saved`, () => api.changeUser(u.id, { roles: next }));
                    }} /></td>
                ))}
                <td>
                  <button onClick={() => {
                    const pw = window.prompt(`New password for ${u.username} (8 characters or more):`);
                    if (pw) void act(`${u.username}: password reset (their sessions ended)`, () => api.changeUser(u.id, { password: pw }));
                  }}>Reset password</button>
                  {" "}
                  <button disabled={u.id === me.id} onClick={() => {
                    if (window.confirm(`Delete the user ${u.username}?`)) void act(`${u.username} deleted`, () => api.deleteUser(u.id));
                  }}>Delete</button>
                </td>
              </tr>
            ))}
          </tbody>
        </table>
      )}
      <form className="new-project" aria-label="New user" onSubmit={(e) => {
        e.preventDefault();
        void act(`${name} created`, () => api.createUser(name, password, roles)).then(() => { setName(""); setPassword(""); });
      }}>
        <h2>New user</h2>
        <label>User name<input value={name} onChange={(e) => setName(e.target.value)} required pattern="[A-Za-z0-9_.@\-]+" /></label>
        <label>Password<input type="password" value={password} onChange={(e) => setPassword(e.target.value)} required minLength={8} autoComplete="new-password" /></label>
        <fieldset><legend>Roles</legend>
          {ROLES.map((r) => <label key={r}><input type="checkbox" checked={roles.includes(r)} onChange={(e) => setRoles(toggle(roles, r, e.target.checked))} /> {r}</label>)}
        </fieldset>
        <button type="submit">Create user</button>
      </form>
    </main>
  );
}
