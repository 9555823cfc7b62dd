/**
 * The e2e oracle for backfilled values: the drone's on-board MCAP archive read
 * with @mcap/core (the TypeScript reader, independent of the PubBroker's C++
 * writer and of the Python code that aggregates in the product), and each
 * window's aggregate recomputed here from the raw samples, by the PubBroker's
 * documented window rule: the samples whose log time is in [start, end).
 *
 * Window times reach the browser as seconds in a double (about 0.25 µs
 * apart at today's dates), so a sample stamped within EDGE_NS of a window's
 * edge may belong to either side: every choice for those few is tried.
 */
import { readdirSync, readFileSync, statSync } from "node:fs";
import { join } from "node:path";
import { McapStreamReader } from "@mcap/core";
import { decompress as zstd } from "fzstd";
import lz4 from "lz4js";

const EDGE_NS = 2000n;

const decompressHandlers = {
  zstd: (data, size) => zstd(data, new Uint8Array(Number(size))),
  lz4: (data, size) => Uint8Array.from(lz4.decompress(data, Number(size))),
};

function mcapFiles(dir) {
  const out = [];
  for (const name of readdirSync(dir)) {
    const path = join(dir, name);
    if (statSync(path).isDirectory()) out.push(...mcapFiles(path));
    else if (name.endsWith(".mcap")) out.push(path);
  }
  return out.sort();
}

/**
 * Every sample of `topic` in the archive directory (closed files, and the
 * complete chunks of the file being written): `[{ ns: bigint, value: number }]`
 * in log-time order.
 */
export function readTopic(dir, topic) {
  const samples = [];
  for (const path of mcapFiles(dir)) {
    const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
    reader.append(new Uint8Array(readFileSync(path)));
    const ids = new Set();
    try {
      for (let rec; (rec = reader.nextRecord()) !== undefined; ) {
        if (rec.type === "Channel" && rec.topic === topic) ids.add(rec.id);
        else if (rec.type === "Message" && ids.has(rec.channelId)) {
          samples.push({ ns: rec.logTime, value: Number(JSON.parse(new TextDecoder().decode(rec.data)).value) });
        }
      }
    } catch {
      // the file being written ends in a chunk not yet whole: what came before counts
    }
  }
  return samples.sort((a, b) => (a.ns < b.ns ? -1 : a.ns > b.ns ? 1 : 0));
}

/** The aggregate of raw values, as a delivered value carries it: `{ value, count }` (value null when empty). */
export function aggregate(aggregation, values) {
  const n = values.length;
  const value = n === 0 && aggregation !== "COUNT" ? null : {
    MIN: () => Math.min(...values),
    MAX: () => Math.max(...values),
    FIRST: () => values[0],
    LAST: () => values[n - 1],
    SUM: () => values.reduce((a, b) => a + b, 0),
    AVERAGE: () => values.reduce((a, b) => a + b, 0) / n,
    COUNT: () => n,
  }[aggregation]?.();
  if (value === undefined) throw new Error(`the oracle has no ${aggregation}`);
  return { value, count: n };
}

/** Does a delivered value equal the oracle's? float32 topics arrive rounded to float32. */
function same(aggregation, got, want) {
  if (want === null) return got === null;
  if (aggregation === "AVERAGE" || aggregation === "SUM") return Math.abs(got - want) <= 1e-5 * Math.max(1, Math.abs(want));
  return got === want || got === Math.fround(want);
}

/** The window's samples for each way of placing the samples stamped at its edges. */
function windowChoices(samples, startNs, endNs) {
  const sure = [];
  const edge = [];
  for (const s of samples) {
    if (s.ns < startNs - EDGE_NS || s.ns >= endNs + EDGE_NS) continue;
    const near = (b) => (s.ns > b ? s.ns - b : b - s.ns) <= EDGE_NS;
    if (near(startNs) || near(endNs)) edge.push(s);
    else sure.push(s);
  }
  if (edge.length > 6) throw new Error(`${edge.length} samples within ${EDGE_NS} ns of a window edge`);
  const out = [];
  for (let mask = 0; mask < 1 << edge.length; mask += 1) {
    const picked = edge.filter((_, i) => mask & (1 << i));
    out.push([...sure, ...picked].sort((a, b) => (a.ns < b.ns ? -1 : 1)).map((s) => s.value));
  }
  return out;
}

const toNs = (seconds) => BigInt(Math.round(Number(seconds) * 1e6)) * 1000n;

/**
 * Checks table rows `{ start, end, value, count }` (seconds and the value as
 * the page holds them, `count` null when not shown) of one subscription
 * against the archive's samples of its topic. Returns the mismatches in words
 * (empty: every row holds the oracle's value).
 */
export function checkRows(samples, aggregation, rows) {
  const wrong = [];
  for (const r of rows) {
    const choices = windowChoices(samples, toNs(r.start), toNs(r.end));
    const answers = choices.map((vs) => aggregate(aggregation, vs));
    const ok = answers.some((a) => same(aggregation, r.value, a.value)
      && (r.count === null || aggregation !== "AVERAGE" || r.count === a.count));
    if (!ok) {
      wrong.push(`window ${r.start}–${r.end}: shown ${r.value}${r.count === null ? "" : ` (${r.count} samples)`}, `
        + `archive ${answers.map((a) => `${a.value} (${a.count} samples)`).join(" or ")}`);
    }
  }
  return wrong;
}
