import { finite } from "../../core/numberFormat";
import { formatHours, type ArchiveSpace } from "../../core/archiveSpace";

/** The on-board archive's free space and hours left at the current rate; an
 * alert under the PubBroker's low-space threshold, on a full disk, or with
 * little time left (core/archiveSpace.ts decides). */
export function ArchiveSpaceNote({ space }: { space: ArchiveSpace }) {
  const mb = finite(space.diskFreeMb);
  const free = mb === null ? "—" : `${Math.round(mb).toLocaleString()} MiB free`;
  const left = space.hoursLeft === null ? "" : ` · ${formatHours(space.hoursLeft)} of archive left at the current rate`;
  const what = space.state === "full" ? "archive disk FULL: samples wait in memory"
    : space.state === "low" ? "archive disk low" : "archive";
  return space.warn
    ? <strong className="behind archive-space" role="alert"> · {what}: {free}{left}</strong>
    : <span className="archive-space"> · {what}: {free}{left}</span>;
}
