/**
 * The vehicle on the map: where it heads (course over ground from its last
 * two distinct fixes, degrees clockwise from north) and what the track is
 * coloured by at first (a value that varies along the way, such as water
 * temperature, rather than the drone's own motion, which the first
 * subscription of a model, an accelerometer, usually is).
 *
 * @example
 *   courseDeg([{ east: 0, north: 0 }, { east: 10, north: 0 }]) // 90: heading east
 */
export interface Fix { east: number; north: number }

/** Course over ground in degrees [0, 360), or null with fewer than two distinct fixes. */
export function courseDeg(points: readonly Fix[]): number | null {
  const last = points[points.length - 1];
  for (let i = points.length - 2; i >= 0 && last; i--) {
    const de = last.east - points[i].east, dn = last.north - points[i].north;
    if (Math.hypot(de, dn) > 0.01) return ((Math.atan2(de, dn) * 180) / Math.PI + 360) % 360;
  }
  return null;
}

/** Units of the drone's own motion (colouring a track by them says little about the place). */
const MOTION_UNITS = new Set(["m/s²", "rad", "rad/s", "deg", "°", "°/s", "m/s", "m"]);

/** The colour channel to start with: the first subscription that is not the drone's own motion, else the first. */
export function defaultColour(choices: ReadonlyArray<{ channel: string; unit: string }>): string {
  return (choices.find((c) => c.unit && !MOTION_UNITS.has(c.unit)) ?? choices[0])?.channel ?? "";
}
