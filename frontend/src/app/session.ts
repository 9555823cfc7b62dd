/**
 * The login session: token and user, kept in sessionStorage so a reload stays
 * logged in (the storage is passed in; nothing is read at import time).
 */
import type { User } from "../api/types";

export interface Session {
  token: string;
  user: User;
}

const KEY = "modd.session";

export function loadSession(storage: Storage): Session | null {
  try {
    const raw = storage.getItem(KEY);
    return raw ? (JSON.parse(raw) as Session) : null;
  } catch {
    return null;
  }
}

export function saveSession(storage: Storage, s: Session | null): void {
  if (s) storage.setItem(KEY, JSON.stringify(s));
  else storage.removeItem(KEY);
}
