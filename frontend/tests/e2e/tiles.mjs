/**
 * A map tile server on loopback for the map step (no network in tests):
 * answers /{z}/{x}/{y}.png with a 256×256 PNG (pale green, a darker border,
 * so tiles show as a grid), with CORS like public tile servers, and records
 * every tile asked for. Anything else is a 404.
 */
import { createServer } from "node:http";
import { deflateSync } from "node:zlib";

/** RGB of a tile's inside and of its border, for pixel checks. */
export const TILE_FILL = [200, 230, 201];
export const TILE_BORDER = [120, 160, 122];

const CRC_TABLE = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; k += 1) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});

function crc32(buf) {
  let c = 0xffffffff;
  for (const b of buf) c = CRC_TABLE[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

function chunk(type, data) {
  const len = Buffer.alloc(4);
  len.writeUInt32BE(data.length);
  const body = Buffer.concat([Buffer.from(type, "ascii"), data]);
  const crc = Buffer.alloc(4);
  crc.writeUInt32BE(crc32(body));
  return Buffer.concat([len, body, crc]);
}

/** A w×h RGB PNG, each pixel from `rgb(x, y)`. */
export function png(w, h, rgb) {
  const raw = Buffer.alloc((w * 3 + 1) * h);
  for (let y = 0; y < h; y += 1) {
    raw[y * (w * 3 + 1)] = 0; // filter: none
    for (let x = 0; x < w; x += 1) raw.set(rgb(x, y), y * (w * 3 + 1) + 1 + x * 3);
  }
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(w, 0);
  ihdr.writeUInt32BE(h, 4);
  ihdr.set([8, 2, 0, 0, 0], 8); // 8 bits, truecolour
  return Buffer.concat([Buffer.from([137, 80, 78, 71, 13, 10, 26, 10]), chunk("IHDR", ihdr),
    chunk("IDAT", deflateSync(raw)), chunk("IEND", Buffer.alloc(0))]);
}

const TILE = png(256, 256, (x, y) => (x < 2 || y < 2 ? TILE_BORDER : TILE_FILL));
/** The PNG of every tile (a tile folder's files too). */
export const tilePng = TILE;

/** Starts the server on 127.0.0.1 (a free port); `requests` lists the tiles asked for ({ z, x, y, host }). */
export async function startTileServer() {
  const requests = [];
  const server = createServer((req, res) => {
    const m = /^\/(\d+)\/(-?\d+)\/(-?\d+)\.png$/.exec(req.url ?? "");
    if (!m) { res.writeHead(404).end(); return; }
    requests.push({ z: Number(m[1]), x: Number(m[2]), y: Number(m[3]), host: req.headers.host });
    res.writeHead(200, { "content-type": "image/png", "access-control-allow-origin": "*", "cache-control": "max-age=3600" });
    res.end(TILE);
  });
  await new Promise((resolve) => server.listen(0, "127.0.0.1", resolve));
  const { port } = server.address();
  return { origin: `http://127.0.0.1:${port}`, port, requests, close: () => new Promise((r) => server.close(r)) };
}

/** The slippy-map tile holding (lat, lon) at zoom z (the OSM wiki's formula). */
export function tileOf(lat, lon, z) {
  const n = 2 ** z, r = (lat * Math.PI) / 180;
  return [Math.floor(((lon + 180) / 360) * n), Math.floor(((1 - Math.asinh(Math.tan(r)) / Math.PI) / 2) * n)];
}
