/**
 * "Communication lost" across the top of every view while the drone's link
 * is down, with why and the time since the last frame. While it shows, the
 * diagram draws the link edge broken (app/views.css: `.workbench:has(.link-banner)`).
 */
import { useDroneName } from "./fleetFocus";
import { formatAge } from "../core/linkHealth";
import { useLinkHealth } from "./useLinkHealth";

export function LinkBanner() {
  const drone = useDroneName();
  const link = useLinkHealth();
  if (!link.down) return null;
  return (
    <div className="link-banner" role="alert" aria-label="Link lost" data-testid="link-banner">
      <span>Communication lost with {drone}</span>
      <span>{link.reason}</span>
      <span data-testid="since-last-frame">{link.sinceLastFrameS === null ? "no frame received yet" : `last frame ${formatAge(link.sinceLastFrameS)} ago`}</span>
    </div>
  );
}
