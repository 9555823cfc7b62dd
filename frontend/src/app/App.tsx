/** Log in → choose a project → the workbench. */
import { useCallback, useState } from "react";
import type { Project } from "../api/types";
import { LoginPage } from "./LoginPage";
import { ProjectsPage } from "./ProjectsPage";
import { Workbench } from "./Workbench";
import { useServices } from "./services";
import type { Session } from "./session";

interface Props {
  initial: Session | null;
  onSession: (s: Session | null) => void;
}

export function App({ initial, onSession }: Props) {
  const { api } = useServices();
  const [session, setSession] = useState<Session | null>(initial);
  const [project, setProject] = useState<Project | null>(null);

  const login = useCallback((s: Session) => { onSession(s); setSession(s); }, [onSession]);
  const logout = useCallback(() => {
    void api.logout().catch(() => undefined);
    onSession(null);
    setSession(null);
    setProject(null);
  }, [api, onSession]);

  if (!session) return <LoginPage onLogin={login} />;
  if (!project) return <ProjectsPage user={session.user.username} onOpen={setProject} onLogout={logout} />;
  return <Workbench key={project.id} project={project} user={session.user} onLogout={logout} onProjects={() => setProject(null)} />;
}
