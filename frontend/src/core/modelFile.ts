/**
 * Reading a model file the user picked: which notation its name says, and its
 * text in the encoding it was written in. Files of the original MoDD tool
 * (`.collector`) were often saved by Eclipse in windows-1252: bytes that are
 * not UTF-8 are read as windows-1252, and the caller is told so.
 */

export type ModelFormat = "modd" | "json";

/** File extensions the import accepts (the `accept` of the file input). */
export const MODEL_FILE_TYPES = ".modd,.collector,.json";

export interface ModelFile {
  /** Project name derived from the file name (extension dropped, unsafe characters replaced). */
  name: string;
  format: ModelFormat;
  text: string;
  /** "utf-8" or "windows-1252" (then the user is told). */
  encoding: "utf-8" | "windows-1252";
}

// windows-1252 differs from Latin-1 only in 0x80-0x9f (the five undefined bytes
// keep their Latin-1 meaning). Written out here because some runtimes' TextDecoder
// treat the label "windows-1252" as Latin-1.
const CP1252_80_9F = "\u20ac\u0081\u201a\u0192\u201e\u2026\u2020\u2021\u02c6\u2030\u0160\u2039\u0152\u008d\u017d\u008f\u0090\u2018\u2019\u201c\u201d\u2022\u2013\u2014\u02dc\u2122\u0161\u203a\u0153\u009d\u017e\u0178";

function decodeWindows1252(bytes: Uint8Array): string {
  let out = "";
  for (const b of bytes) out += b >= 0x80 && b < 0xa0 ? CP1252_80_9F[b - 0x80] : String.fromCharCode(b);
  return out;
}

export function decodeModelBytes(bytes: Uint8Array): { text: string; encoding: ModelFile["encoding"] } {
  try {
    // fatal: throw on the first byte that is not UTF-8; ignoreBOM=false strips a BOM
    return { text: new TextDecoder("utf-8", { fatal: true }).decode(bytes), encoding: "utf-8" };
  } catch {
    return { text: decodeWindows1252(bytes), encoding: "windows-1252" };
  }
}

export function modelFile(fileName: string, bytes: Uint8Array): ModelFile {
  const format: ModelFormat = /\.json$/i.test(fileName) ? "json" : "modd";
  const name = fileName.replace(/\.(modd|collector|json)$/i, "").replace(/[^A-Za-z0-9_. -]/g, "_")
    .replace(/^[^A-Za-z0-9_]+/, "") || "imported";
  return { name, format, ...decodeModelBytes(bytes) };
}
