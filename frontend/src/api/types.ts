/**
 * Bodies of the backend's REST API (backend/src/modd_backend/schemas.py and
 * routers; served as /openapi.json). The model itself is typed by
 * core/model.gen.ts, generated from the metamodel schema.
 */
import type { ModdModel } from "../core/model.gen";
import type { Diagnostic } from "../core/diagnostics";
import type { PlanJson } from "../core/plan";
import type { Role } from "../core/roles";

export interface User {
  id: number;
  username: string;
  roles: Role[];
}

export interface LoginResult {
  token: string;
  user: User;
}

export interface Project {
  id: number;
  name: string;
  created_at: string;
  created_by: string;
  head_revision: number;
}

export interface Version {
  project_id: number;
  revision: number;
  valid: boolean;
  author: string;
  message: string;
  created_at: string;
}

export interface ModelVersion extends Version {
  model: ModdModel;
  diagnostics: Diagnostic[];
}

export interface ValidateResult {
  ok: boolean;
  model: ModdModel | null;
  diagnostics: Diagnostic[];
}

export interface PlanResult {
  ok: boolean;
  plan: PlanJson | null;
  diagnostics: Diagnostic[];
  elapsed_ms: number;
}

export type ModelInput = { model: ModdModel } | { text: string; format?: "modd" | "json" };
