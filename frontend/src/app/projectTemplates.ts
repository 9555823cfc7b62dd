/**
 * What a new project can start from: empty, scenario 1 of the MoDD paper, or
 * the demo mission of `make run`. The model files are the repository's own
 * (metamodel/), bundled as text at build time and imported through the
 * backend like any .modd file, so they are parsed by the one parser.
 */
import scenario1 from "@schema/tests/data/scenario1_datacollector.modd?raw";
import demo from "@schema/examples/demo.modd?raw";

export interface ProjectTemplate {
  id: "empty" | "scenario1" | "demo";
  title: string;
  /** .modd text; null: the empty model of the drone name given. */
  text: string | null;
}

export const PROJECT_TEMPLATES: readonly ProjectTemplate[] = [
  { id: "empty", title: "Empty (a drone, its two brokers)", text: null },
  { id: "scenario1", title: "Scenario 1 of the paper (accelerometer, seven subscriptions)", text: scenario1 },
  { id: "demo", title: "The demo mission (scenario 1, MAVLink position, water probes)", text: demo },
];
