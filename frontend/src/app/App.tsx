/** Log in → choose a project → the workbench. */
import { useCallback, useEffect, useState } from "react";
import type { Project } from "../api/types";
import { LoginPage } from "./LoginPage";
import { ProjectsPage } from "./ProjectsPage";
import { Workbench } from "./Workbench";
import { UsersPage } from "./UsersPage";
import { useServices } from "./services";
import type { Session } from "./session";
import { goTo, parseRoute } from "./routes";

interface Props {
  initial: Session | null;
  onSession: (s: Session | null) => void;
}

export function App({ initial, onSession }: Props) {
  const { api } = useServices();
  const [session, setSession] = useState<Session | null>(initial);
  const [project, setProject] = useState<Project | null>(null);
  // The address as the page was opened (a deep link): kept through the login.
  const [route, setRoute] = useState(() => parseRoute(window.location.pathname));
  const [routeError, setRouteError] = useState<string | null>(null);
  const [usersPage, setUsersPage] = useState(() => window.location.pathname === "/users");
  const showUsers = useCallback((on: boolean) => {
    window.history.pushState(null, "", on ? "/users" : "/");
    setUsersPage(on);
  }, []);

  useEffect(() => {
    const onPop = () => { setRoute(parseRoute(window.location.pathname)); setUsersPage(window.location.pathname === "/users"); };
    window.addEventListener("popstate", onPop);
    return () => window.removeEventListener("popstate", onPop);
  }, []);
  // A project named in the address opens once logged in.
  useEffect(() => {
    if (!session) return;
    if (route.project === null) { setProject(null); return; }
    if (project?.id === route.project) return;
    let live = true;
    api.getProject(route.project).then(
      (p) => { if (live) { setProject(p); setRouteError(null); } },
      (e: Error) => { if (live) { setRouteError(`project ${route.project}: ${e.message}`); goTo({ project: null, view: null, panel: null }); setRoute(parseRoute("/")); } },
    );
    return () => { live = false; };
  }, [api, session, route, project]);

  const open = useCallback((p: Project) => {
    goTo({ project: p.id, view: null, panel: null }, true);
    setProject(p);
    setRoute({ project: p.id, view: null, panel: null });
  }, []);
  const toProjects = useCallback(() => {
    goTo({ project: null, view: null, panel: null }, true);
    setProject(null);
    setRoute({ project: null, view: null, panel: null });
  }, []);
  const login = useCallback((s: Session) => { onSession(s); setSession(s); }, [onSession]);
  const logout = useCallback(() => {
    void api.logout().catch(() => undefined);
    onSession(null);
    setSession(null);
    setProject(null);
  }, [api, onSession]);

  if (!session) return <LoginPage onLogin={login} />;
  if (usersPage && session.user.roles.includes("admin")) return <UsersPage me={session.user} onBack={() => showUsers(false)} />;
  if (route.project !== null && project?.id !== route.project) return <main className="loading" role="status">Opening project {route.project}…</main>;
  if (!project) return <>{routeError && <p className="error" role="alert">{routeError}</p>}<ProjectsPage user={session.user.username} onOpen={open} onLogout={logout}
    onUsers={session.user.roles.includes("admin") ? () => showUsers(true) : undefined} /></>;
  return <Workbench key={project.id} project={project} user={session.user} route={route} onLogout={logout} onProjects={toProjects} />;
}
