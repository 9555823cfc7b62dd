/**
 * What a download's headers say: the name the backend gave the file
 * (Content-Disposition, RFC 6266: `filename*=UTF-8''…` first, else
 * `filename="…"`) and an export's notes (`X-Modd-Notes`, a JSON list).
 *
 *   filenameOf('attachment; filename="usv-dataset-20260921T141320Z-20260921T151320Z.nc"')
 *   // "usv-dataset-20260921T141320Z-20260921T151320Z.nc"
 */
import type { DatasetFile } from "./types";

/** The file name a Content-Disposition gives (no directory part), or null. */
export function filenameOf(header: string | null): string | null {
  if (!header) return null;
  const star = /filename\*\s*=\s*(?:UTF-8|utf-8)''([^;]+)/.exec(header);
  let name: string | null = null;
  if (star) {
    try { name = decodeURIComponent(star[1].trim()); } catch { name = null; }
  }
  if (name === null) {
    const plain = /filename\s*=\s*(?:"((?:[^"\\]|\\.)*)"|([^;\s]+))/.exec(header);
    name = plain ? (plain[1] ?? plain[2]).replace(/\\(.)/g, "$1") : null;
  }
  const base = name?.split(/[/\\]/).pop()?.trim();
  return base ? base : null;
}

/** The notes of an export (`X-Modd-Notes`); none when absent or unreadable. */
export function notesOf(header: string | null): string[] {
  if (!header) return [];
  try {
    const v: unknown = JSON.parse(header);
    return Array.isArray(v) ? v.filter((n): n is string => typeof n === "string") : [];
  } catch {
    return [];
  }
}

/** An export's file as the backend named it (`fallback` only when it gave no name). */
export function datasetFile(blob: Blob, headers: Headers, fallback: string): DatasetFile {
  return {
    blob,
    name: filenameOf(headers.get("Content-Disposition")) ?? fallback,
    notes: notesOf(headers.get("X-Modd-Notes")),
  };
}
