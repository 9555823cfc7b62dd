/**
 * The login session. The workbench's session is an HttpOnly, SameSite=Strict
 * cookie set by the backend, so it spans tabs and survives a reload, and page
 * scripts never see the token; what the page keeps is the user and the CSRF
 * token, both read back from /api/auth/me at start.
 */
import type { User } from "../api/types";

export interface Session {
  /** Bearer token (API clients only); null with the cookie session. */
  token: string | null;
  csrf?: string | null;
  user: User;
}

/** The session of the cookie this browser holds, or null (not logged in). */
export async function restoreSession(me: () => Promise<User & { csrf?: string | null }>): Promise<Session | null> {
  try {
    const { csrf, ...user } = await me();
    return { token: null, csrf: csrf ?? null, user };
  } catch {
    return null;
  }
}
