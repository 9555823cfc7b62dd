/**
 * What a deploy of `revision` would change on the drone: the model that runs
 * (its last acked deployment, from any project) against the candidate, in
 * words (core/changeWords), with the plan's consequences (both models
 * planned by the backend's planning engine, core/planDiff), and whether the
 * candidate may be deployed at all (an invalid revision may not).
 */
import { topicLabel } from "../../core/topicLabel";
import { describeChanges, type ChangeSentence } from "../../core/changeWords";
import { diagnosticsInWords, type WordedDiagnostic } from "../../core/diagnosticWords";
import { planChanges, type PlanChange } from "../../core/planDiff";
import type { Api } from "../../api/client";
import type { DeployedDiff, ModelVersion, Project } from "../../api/types";

export interface DeployReview {
  diff: DeployedDiff;
  candidate: ModelVersion;
  /** Set when the drone runs another project's model: its name. */
  otherProject: string | null;
  changes: ChangeSentence[];
  consequences: PlanChange[];
  /** Why the candidate cannot be deployed (its errors in words); empty when it can. */
  blockers: WordedDiagnostic[];
}

export async function loadDeployReview(api: Api, projectId: number, revision: number | undefined): Promise<DeployReview> {
  const [diff, candidate, projects] = await Promise.all([
    api.deployedDiff(projectId), api.readModel(projectId, revision), api.listProjects().catch((): Project[] => []),
  ]);
  const running = diff.deployed ? await api.readModel(diff.deployed.project_id, diff.deployed.revision).catch(() => null) : null;
  const blockers = candidate.valid ? [] : diagnosticsInWords(candidate.model, candidate.diagnostics).filter((d) => d.severity === "error");
  const [before, after] = await Promise.all([
    running ? api.plan({ model: running.model }).catch(() => null) : Promise.resolve(null),
    candidate.valid ? api.plan({ model: candidate.model }).catch(() => null) : Promise.resolve(null),
  ]);
  const otherId = diff.deployed && !diff.same_project ? diff.deployed.project_id : null;
  return {
    diff,
    candidate,
    otherProject: otherId === null ? null : projects.find((p) => p.id === otherId)?.name ?? `#${otherId}`,
    changes: describeChanges(running?.model ?? {}, candidate.model),
    consequences: before?.plan && after?.plan
      ? planChanges(before.plan, after.plan, (t) => topicLabel([candidate.model, running?.model], t)) : [],
    blockers: blockers.length || candidate.valid ? blockers
      : [{ severity: "error", element: "the model", elementId: "drone", text: `revision ${candidate.revision} is not valid`, pointer: null }],
  };
}
