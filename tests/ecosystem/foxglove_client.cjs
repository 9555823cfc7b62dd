// A Foxglove client in a test: @foxglove/ws-protocol's FoxgloveClient on a
// WebSocket asking for the SDK's subprotocol "foxglove.sdk.v1". It subscribes
// to every advertised channel, records advertise/unadvertise and every
// message (JSON-decoded), and prints one JSON report at the end.
//   node --experimental-websocket foxglove_client.cjs URL SECONDS [--seek NS --after S]
//        [--subscribe-gap MS]
// --subscribe-gap subscribes to the advertised channels one at a time, MS
// apart, as a viewer whose panels mount one after the other (Lichtblick).
// --seek sends a playback control request (Play, seek to NS) after S seconds:
// FoxgloveClient has no playback API, so the request is written on the same
// socket with the SDK's layout (opcode 3: command u8, speed f32, had_seek u8,
// seek_time u64, request id length u32, request id); PlaybackState messages
// (server opcode 5) are recorded and not handed to FoxgloveClient, which does
// not know them.
"use strict";
const { FoxgloveClient } = require("@foxglove/ws-protocol");

const SUBPROTOCOL = "foxglove.sdk.v1";
const KNOWN_SERVER_OPCODES = new Set([1, 2, 3, 4]);

class FilteringSocket {
  // The IWebSocket FoxgloveClient needs, over Node's WebSocket.
  constructor(url, report) {
    this.ws = new WebSocket(url, [SUBPROTOCOL]);
    this.ws.binaryType = "arraybuffer";
    this.report = report;
    this.onopen = this.onclose = this.onerror = this.onmessage = undefined;
    this.ws.onopen = (e) => { this.report.protocol = this.ws.protocol; this.onopen && this.onopen(e); };
    this.ws.onclose = (e) => this.onclose && this.onclose(e);
    this.ws.onerror = (e) => this.onerror && this.onerror(e);
    this.ws.onmessage = (e) => {
      if (e.data instanceof ArrayBuffer) {
        const view = new DataView(e.data);
        const op = view.getUint8(0);
        if (!KNOWN_SERVER_OPCODES.has(op)) {
          if (op === 5 && e.data.byteLength >= 15) {
            this.report.playbackStates.push({
              status: view.getUint8(1),
              currentTime: view.getBigUint64(2, true).toString(),
              atMessage: this.report.received,
            });
          }
          return;
        }
      }
      this.onmessage && this.onmessage(e);
    };
  }
  get binaryType() { return this.ws.binaryType; }
  set binaryType(v) { this.ws.binaryType = v; }
  get protocol() { return this.ws.protocol; }
  close() { this.ws.close(); }
  send(data) { this.ws.send(data); }
}

function playbackRequest(seekNs, requestId) {
  const id = new TextEncoder().encode(requestId);
  const buf = new ArrayBuffer(1 + 1 + 4 + 1 + 8 + 4 + id.length);
  const v = new DataView(buf);
  v.setUint8(0, 3); // client binary opcode: playback control request
  v.setUint8(1, 0); // Play
  v.setFloat32(2, 1.0, true);
  v.setUint8(6, 1);
  v.setBigUint64(7, BigInt(seekNs), true);
  v.setUint32(15, id.length, true);
  new Uint8Array(buf, 19).set(id);
  return new Uint8Array(buf);
}

function main() {
  const [url, seconds, ...rest] = process.argv.slice(2);
  const seekAt = rest.indexOf("--seek");
  const seek = seekAt >= 0 ? rest[seekAt + 1] : null;
  const afterAt = rest.indexOf("--after");
  const after = afterAt >= 0 ? Number(rest[afterAt + 1]) : 1;
  const gapAt = rest.indexOf("--subscribe-gap");
  const gapMs = gapAt >= 0 ? Number(rest[gapAt + 1]) : 0;
  let pending = Promise.resolve(); // subscriptions in order, gapMs apart
  const report = {
    protocol: null, serverInfo: null, advertised: [], unadvertised: [], errors: [],
    statuses: [], resubscribed: [],
    messages: {}, received: 0, playbackStates: [], seekSentAtMessage: null,
  };
  const socket = new FilteringSocket(url, report);
  const client = new FoxgloveClient({ ws: socket });
  const topics = new Map(); // channel id -> topic
  const subscriptions = new Map(); // subscription id -> topic
  const decoder = new TextDecoder();
  client.on("serverInfo", (info) => { report.serverInfo = info; });
  client.on("error", (e) => report.errors.push(String(e && e.message ? e.message : e)));
  client.on("advertise", (channels) => {
    for (const ch of channels) {
      topics.set(ch.id, ch.topic);
      report.advertised.push({ topic: ch.topic, encoding: ch.encoding, schemaName: ch.schemaName,
                               schema: ch.schema });
      if (gapMs > 0) {
        pending = pending.then(() => new Promise((done) => setTimeout(() => {
          if (topics.has(ch.id)) subscriptions.set(client.subscribe(ch.id), ch.topic);
          done();
        }, gapMs)));
      } else {
        subscriptions.set(client.subscribe(ch.id), ch.topic);
      }
    }
  });
  client.on("unadvertise", (ids) => {
    for (const id of ids) { report.unadvertised.push(topics.get(id)); topics.delete(id); }
  });
  // foxglove-sdk advertises a new channel before it records it as advertised
  // to the client (connected_client.rs, advertise_channels): a client that
  // subscribes at once can be told "Unknown channel ID" for a channel it was
  // just offered. A robust client subscribes again while the channel stands.
  const retries = new Map(); // channel id -> re-subscriptions
  client.on("status", (status) => {
    const m = /Unknown channel ID: (\d+)/.exec(status.message || "");
    if (!m) { report.statuses.push(status.message); return; }
    const id = Number(m[1]);
    const n = retries.get(id) || 0;
    if (!topics.has(id)) { report.statuses.push(status.message); return; } // withdrawn since
    if (n >= 5) { report.errors.push(status.message); return; }
    retries.set(id, n + 1);
    report.resubscribed.push(topics.get(id));
    setTimeout(() => {
      if (topics.has(id)) subscriptions.set(client.subscribe(id), topics.get(id));
    }, 50 * (n + 1));
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const topic = subscriptions.get(subscriptionId);
    const msg = JSON.parse(decoder.decode(data));
    (report.messages[topic] ||= []).push({ logTime: timestamp.toString(), msg, recvMs: Date.now() });
    report.received += 1;
  });
  if (seek !== null) {
    setTimeout(() => {
      report.seekSentAtMessage = report.received;
      socket.send(playbackRequest(seek, "seek-1"));
    }, after * 1000);
  }
  setTimeout(() => {
    client.close();
    process.stdout.write(JSON.stringify(report) + "\n", () => process.exit(0));
  }, Number(seconds) * 1000);
}

main();
