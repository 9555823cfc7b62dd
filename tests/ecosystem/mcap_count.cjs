// Reads MCAP files with the TypeScript reader @mcap/core (independent of the
// Python `mcap` package) and prints, per file, the message count per topic as
// JSON. Closed files go through McapIndexedReader (summary, chunk indexes);
// with --stream, files are read front to back with McapStreamReader, which is
// how a crashed file (no summary, maybe a torn tail) is read.
//   NODE_PATH=frontend/node_modules node mcap_count.cjs [--stream] FILE...
"use strict";
const fs = require("node:fs");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const { decompress: zstd } = require("fzstd");
const lz4 = require("lz4js");

const decompressHandlers = {
  zstd: (data, size) => zstd(data, new Uint8Array(Number(size))),
  lz4: (data, size) => {
    const out = lz4.decompress(data, Number(size));
    return out instanceof Uint8Array ? out : Uint8Array.from(out);
  },
};

function readable(path) {
  const fd = fs.openSync(path, "r");
  const size = BigInt(fs.fstatSync(fd).size);
  return {
    size: async () => size,
    read: async (offset, length) => {
      const buf = Buffer.alloc(Number(length));
      fs.readSync(fd, buf, 0, Number(length), Number(offset));
      return new Uint8Array(buf.buffer, buf.byteOffset, buf.length);
    },
  };
}

async function indexed(path) {
  const reader = await McapIndexedReader.Initialize({ readable: readable(path), decompressHandlers });
  const counts = {};
  for await (const m of reader.readMessages()) {
    const topic = reader.channelsById.get(m.channelId).topic;
    counts[topic] = (counts[topic] || 0) + 1;
  }
  return { counts, complete: true, error: null };
}

function streamed(path) {
  const reader = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  reader.append(new Uint8Array(fs.readFileSync(path)));
  const topics = new Map();
  const counts = {};
  let complete = false;
  let error = null;
  try {
    for (let rec; (rec = reader.nextRecord()) !== undefined; ) {
      if (rec.type === "Channel") topics.set(rec.id, rec.topic);
      else if (rec.type === "Message") {
        const topic = topics.get(rec.channelId);
        counts[topic] = (counts[topic] || 0) + 1;
      } else if (rec.type === "Footer") complete = true;
    }
  } catch (e) {
    error = String(e.message || e);
  }
  return { counts, complete: complete && reader.done(), error };
}

async function main() {
  const args = process.argv.slice(2);
  const stream = args[0] === "--stream";
  const files = stream ? args.slice(1) : args;
  const out = {};
  for (const f of files) {
    try {
      out[f] = stream ? streamed(f) : await indexed(f);
    } catch (e) {
      out[f] = { counts: null, complete: false, error: String(e.message || e) };
    }
  }
  process.stdout.write(JSON.stringify(out) + "\n");
}

main().catch((e) => {
  process.stderr.write(String(e.stack || e) + "\n");
  process.exit(1);
});
