/**
 * Entry point: builds the services (API client on the page's origin, stream
 * sockets) and renders the app. All configuration is read here, once.
 */
import { StrictMode } from "react";
import { createRoot } from "react-dom/client";
import { createApi } from "./api/client";
import { WebSocketSource, type SocketLike } from "./dataSources/WebSocketSource";
import { App } from "./app/App";
import { ServicesContext, type Services } from "./app/services";
import { restoreSession, type Session } from "./app/session";
import "./app/styles.css";
import "./app/views.css";

let session: Session | null = null;
const onSession = (s: Session | null) => { session = s; };
window.sessionStorage.removeItem("modd.session"); // bearer tokens kept there before the cookie session

const api = createApi({
  baseUrl: "",
  fetch: window.fetch.bind(window),
  token: () => session?.token ?? null,
  csrf: () => session?.csrf ?? null,
  onUnauthorized: () => {
    if (session) { onSession(null); window.location.reload(); }
  },
});

const services: Services = {
  api,
  openStream: (drone) => new WebSocketSource({
    url: api.streamUrl(drone, window.location.origin),
    connect: (url) => new WebSocket(url) as unknown as SocketLike,
  }),
};

void restoreSession(api.me).then((restored) => {
  session = restored;
  createRoot(document.getElementById("root")!).render(
    <StrictMode>
      <ServicesContext.Provider value={services}>
        <App initial={session} onSession={onSession} />
      </ServicesContext.Provider>
    </StrictMode>,
  );
});
