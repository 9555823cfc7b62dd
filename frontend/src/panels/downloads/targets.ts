/**
 * The role zips of the Downloads panel, each titled by what it holds (the
 * generators' targets per role, generators/src/modd_gen/generate.py): a
 * newcomer looking for Python publishers finds them under the integrator's.
 */
export interface DownloadTarget {
  target: "integrator" | "scientist" | "operator";
  title: string;
  who: string;
}

export const TARGETS: DownloadTarget[] = [
  { target: "integrator", title: "Driver stubs (C++ drivers, Python publishers, ROS 2 messages)", who: "Sensor integrator" },
  { target: "scientist", title: "Subscriber stubs (Python, C++)", who: "Scientist" },
  { target: "operator", title: "Broker configurations", who: "Operator" },
];
