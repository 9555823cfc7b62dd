// @vitest-environment jsdom
import { act, render, screen } from "@testing-library/react";
import { afterEach, describe, expect, it, vi } from "vitest";
import type { Api } from "../api/client";
import type { Project } from "../api/types";
import { EMPTY_POLL_MS, ProjectsPage } from "./ProjectsPage";
import { ServicesContext, type Services } from "./services";

const demo = { id: 1, name: "demo", head_revision: 1, created_by: "admin" } as unknown as Project;

function page(listProjects: () => Promise<Project[]>) {
  const services = { api: { listProjects } as unknown as Api, openStream: vi.fn() } as unknown as Services;
  return render(
    <ServicesContext.Provider value={services}>
      <ProjectsPage onOpen={() => {}} user="admin" onLogout={() => {}} />
    </ServicesContext.Provider>,
  );
}

describe("ProjectsPage", () => {
  afterEach(() => { vi.useRealTimers(); });

  it("follows a project that arrives after the page opened (the demo of make run)", async () => {
    vi.useFakeTimers();
    let server: Project[] = [];
    const listProjects = vi.fn(async () => server);
    page(listProjects);
    await act(async () => { await Promise.resolve(); });
    expect(screen.getByText("No project yet.")).toBeTruthy();
    server = [demo];
    await act(async () => { vi.advanceTimersByTime(EMPTY_POLL_MS); await Promise.resolve(); });
    expect(screen.getByRole("button", { name: "demo" })).toBeTruthy();
    const calls = listProjects.mock.calls.length;
    await act(async () => { vi.advanceTimersByTime(EMPTY_POLL_MS * 5); await Promise.resolve(); });
    expect(listProjects.mock.calls.length).toBe(calls); // a list with projects is not polled
  });
});
