// Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit.

export const DELIVERED_VALUE_VERSION = 1;
export const STATUS_VERSION = 1;
export const PLAN_VERSION = 1;
export const PUBBROKER_VERSION = 1;
export const ARCHIVE_RECORD_VERSION = 1;
export const BACKFILL_VERSION = 1;

/** One window of one subscription, as the SubBroker puts it on modd/<drone>/sub/<subscriber> and writes it on a TCP delivery connection (one compact JSON object a line). Producer: runtime/python/src/modd/subbroker/payload.py. Consumers: the backend (stream relay, 3D scene, Foxglove), the generated C++ and Python subscriber clients, the browser's WebSocketSource. docs/subbroker.md, "Delivered values". */
export interface DeliveredValue {
  /** The subscription's name (also the last chunk of the key). */
  subscriber: string;
  /** The topic, drone.sensor.variable. */
  topic: string;
  /** How the window's samples were reduced (the metamodel's Aggregation). */
  aggregation: string;
  /** The subscription's period, an exact decimal string. */
  period_s: string;
  /** The variable's unit (the metamodel's Unit). */
  unit: string;
  /** The running configuration the window belongs to. */
  config_id: number;
  /** The schedule slot of the DATA frame that closed the window. */
  slot: number;
  /** Start of the window [start_ns, end_ns), ns since the Unix epoch on the drone's clock. */
  start_ns: number;
  /** End of the window (exclusive), ns since the Unix epoch on the drone's clock. */
  end_ns: number;
  /** The window's value: a number or boolean, the list of raw samples for ALL, or null when the window had no sample. A number JSON cannot hold (a sum beyond the double range) is the string "Infinity", "-Infinity" or "NaN" (docs/protocol.md, "Values JSON cannot hold"). */
  value: number | boolean | "Infinity" | "-Infinity" | "NaN" | (number | boolean | "Infinity" | "-Infinity" | "NaN")[] | null;
  /** Samples behind the value when the aggregation carries it (AVERAGE, COUNT, ALL), else null. */
  count: number | null;
  /** When the SubBroker delivered it, ns since the Unix epoch on the base station's clock. */
  delivered_ns: number;
  /** Payload version; a reader rejects a higher one. */
  v: number;
  /** Present and true when the window was recomputed from the drone's archive after the link missed it (backfill); absent on live values. */
  backfilled?: boolean;
  /** The window's identity, first part: the drone whose window it is. The identity (drone, subscriber, epoch_ns, window) names the window wherever it was heard (any base station, live or backfilled), so a subscriber joined to several stations keeps one of each (docs/fleet.md). Written by every SubBroker since the fleet; absent from older payloads. */
  drone?: string;
  /** The window's identity: the epoch of the configuration it belongs to (the PubBroker's CONFIG_ACK), ns since the Unix epoch on the drone's clock. */
  epoch_ns?: number;
  /** The window's identity: its index k on the configuration's grid, the window being [epoch_ns + k period, epoch_ns + (k + 1) period). */
  window?: number;
  /** An event subscription's window (ON_CHANGE, THRESHOLD: value is the list of its events' values): each event's sample time, ns since the Unix epoch on the drone's clock (the PubBroker's stamp of the sample, to the microsecond), in value's order; absent for the other aggregations. */
  event_ns?: number[];
  /** An event window: how many events beyond the subscription's worst case (at most N a window) were coalesced into its last event (value's last item is the window's newest event); count is then the window's events, len(value) + coalesced. Absent for the other aggregations. */
  coalesced?: number;
}

/** The SubBroker's status document, put on modd/<drone>/status every status_period_s. Producer: runtime/python/src/modd/subbroker/broker.py (status), status.py (rates), backpressure.py. Consumers: the backend (stream relay, health, Foxglove), `modd up`, the browser's WebSocketSource. docs/subbroker.md, "Status". A new field is added here first. */
export interface SubBrokerStatus {
  /** The drone's name. */
  drone: string;
  /** When the document was made, ns since the Unix epoch (base station clock). */
  time_ns: number;
  /** The link's state. */
  link: LinkState;
  /** The PubBroker endpoint, host:port. */
  endpoint: string;
  /** Last PING round trip, seconds. */
  rtt_s: number | null;
  /** The running configuration, or null before the first CONFIG_ACK. */
  config_id: number | null;
  /** The running configuration's epoch. */
  epoch_ns: number | null;
  /** Link frame bytes read since start. */
  bytes_in: number;
  /** Link frame bytes written since start. */
  bytes_out: number;
  /** DATA frames decoded. */
  data_frames: number;
  /** Frames skipped as bad. */
  skipped_frames: number;
  /** Link sessions opened. */
  connects: number;
  /** When the last DATA frame arrived. */
  last_data_ns: number | null;
  /** The last link error, if any. */
  last_error: string | null;
  /** Values delivered since start. */
  delivered: number;
  /** State files the SubBroker could not use and renamed aside at start (docs/subbroker.md, "State files never stop the SubBroker"); absent when none. */
  state_files_set_aside?: unknown[];
  /** The planner's prediction for the running plan (modd_plan.linkcost), or null. */
  predicted_link_bytes_per_s: PredictedLink | null;
  /** Subscriber names per routed stream key. */
  routes: Record<string, string[]>;
  /** Names of the dynamic subscriptions. */
  dynamic: string[];
  /** TCP delivery senders per subscriber. */
  tcp: Record<string, TcpSender>;
  /** The PubBroker's counters from its last STATUS frame (docs/protocol.md, STATUS). */
  pubbroker: Record<string, number>;
  /** Link bytes read per second since the previous status. */
  bytes_in_per_s?: number | null;
  /** Link bytes written per second. */
  bytes_out_per_s?: number | null;
  /** bytes_in_per_s plus 52 B of IPv4+TCP headers per frame: the figure to hold against predicted drone_to_base. */
  ip_bytes_in_per_s?: number | null;
  /** Whether the SubBroker falls behind the link. */
  behind?: boolean;
  /** How far behind, seconds. */
  lag_s?: number | null;
  /** Largest lag seen. */
  max_lag_s?: number;
  /** Bytes waiting in the receive buffer. */
  recv_backlog_bytes?: number;
  /** Since when it is behind. */
  behind_since_ns?: number | null;
  /** How many times it fell behind. */
  behind_episodes?: number;
  /** What runs (docs/subbroker.md, "Status"): source (configured, deploy or kept), project_id, revision, nonce, deployed_by, deployed_at_ns, resumed_at_ns, running, differs_from_configured. */
  deployment?: unknown;
  /** The base station whose SubBroker sent this status, when several may serve the drone (its configured station, docs/fleet.md): the serving station, since a standby keeps its status to itself. Absent without a station. */
  station?: string;
  /** The link's transport this SubBroker was started with ("": the model's; tcp, udp or serial). */
  transport?: string;
  /** Over udp and serial: the planner's figures for the declared transport (modd_plan.linkbudget: drone_to_base, base_to_drone, share, delays_s, ...), else null. */
  link_budget?: object | null;
  /** Over udp and serial: what the datagram link measures (docs/subbroker.md, "Status"); null over tcp. */
  radio?: RadioStatus | null;
  /** The plug-and-play instruments' health (modd-sensors, docs/sensors.md "Health") from the PubBroker's last STATUS, by sensor name; absent when no instrument reports. Carried as docs/protocol.md, STATUS, "Instruments' health". */
  sensors?: Record<string, SensorHealth>;
  /** Put by `modd up` when it gave up the run (docs/reliability.md, "Base station, store and tools"): the SubBroker is stopped with the rest, so this last status (link `stopped`) says which process ended the run and why; absent otherwise. */
  supervisor?: unknown;
  /** What the drone's on-board processes did with the last deploy, when they run on the SubBroker's machine (modd-subbroker --onboard-model; docs/sensors.md, "Deploying to a running drone"): process name (sensors, mavlink) → its result (ok, problem, and for sensors each instrument's action, state and problem). Absent until a deploy was handed over. */
  onboard?: Record<string, object>;
}

/** A datagram link's figures (modd.subbroker.dglink.DatagramLinkClient.radio_status): the wire bytes/s per direction over the last 10 s, the share of slots lost or repaired, the datagrams refused, and the PubBroker's own counters from its last STATUS. */
export interface RadioStatus {
  transport: "udp" | "serial";
  /** The accepted delay the link runs with (the deployed model's). */
  accepted_delay_s: number;
  /** Drone to base, headers or framing included; null before two samples. */
  wire_bytes_in_per_s: unknown;
  /** Base to drone (NACKs, PINGs, CONFIG), headers or framing included; null before two samples. */
  wire_bytes_out_per_s: unknown;
  /** Share of the slots that were missing (later repaired or not). */
  loss: unknown;
  slots_received: number;
  /** Slots that arrived after a NACK. */
  retransmissions: number;
  /** Slots given up (asked 5 times, or out of the resend ring). */
  slots_lost: number;
  /** Slots missing now and still asked for. */
  slots_missing: number;
  nacks: number;
  datagrams_in: number;
  /** Datagrams whose tag did not verify: dropped, never decoded. */
  forged: number;
  /** Datagrams seen before or older than the replay window: dropped. */
  replayed: number;
  /** Datagrams or serial frames that did not decode (CRC, COBS, layout). */
  malformed: number;
  unknown_config: number;
  handshakes: number;
  /** Datagrams of the drone that other stations' modems heard and forwarded through the mesh (docs/fleet.md, "Diversity reception"); absent without a mesh. */
  heard_elsewhere?: number;
  /** Of those, the ones that brought what this station's own modem had missed (the others were heard here too). */
  heard_elsewhere_used?: number;
  /** The PubBroker's datagram counters from its last STATUS (docs/protocol.md, STATUS fields 24..29); null before its first STATUS. */
  pubbroker: PubBrokerDatagrams | null;
}

/** What the PubBroker counted on its datagram link. */
export interface PubBrokerDatagrams {
  /** Every datagram sent, fragments and resends included. */
  datagrams_sent: number;
  /** Datagrams sent again for NACKs. */
  datagrams_resent: number;
  /** NACKs received. */
  nacks: number;
  /** Slots not sent: no session, or too large for 16 fragments (the archive keeps their samples). */
  slots_dropped: number;
  /** Datagrams received whose tag did not verify. */
  forged: number;
  /** Datagrams received again or older than the replay window. */
  replayed: number;
}

/** State of the SubBroker's link to the PubBroker. */
export type LinkState = "connecting" | "handshake" | "configuring" | "up" | "down" | "stopped";
export const LinkStateValues = ["connecting", "handshake", "configuring", "up", "down", "stopped"] as const;

/** The planner's link-cost estimate, bytes per second (modd_plan.linkcost.LinkCost.to_json). */
export interface PredictedLink {
  drone_to_base: number;
  base_to_drone: number;
  plain_pubsub: number;
  plain_pubsub_acks: number;
  frames_per_s: number;
  saving_ratio: number;
}

/** One TCP delivery connection. */
export interface TcpSender {
  connected: boolean;
  sent: number;
  dropped: number;
}

/** One instrument as modd-sensors counts it since it started; a field a newer modd-sensors appends is kept as field_<i>. */
export interface SensorHealth {
  /** 0 closed (device absent or lost), 1 open, 2 silent (open, no value for 3 periods and at least 2 s). */
  state?: number;
  /** Sentences, lines or Modbus replies that passed every check. */
  lines_ok?: number;
  /** Refused: checksum, form, CRC, truncated, garbage. */
  lines_bad?: number;
  /** Times the device was reopened after a loss. */
  reconnects?: number;
  /** Receive time of the last value, ms since the Unix epoch (drone clock); 0: none yet. */
  last_value_ms?: number;
  /** Samples handed to the publishers. */
  values?: number;
  /** Mapped fields with no value in a good line. */
  missing?: number;
  /** Samples the publisher refused at the call. */
  refused?: number;
  /** Modbus requests with no complete reply in time. */
  timeouts?: number;
  /** Modbus exception replies. */
  exceptions?: number;
  /** Times the instrument fell silent. */
  silences?: number;
  /** Good lines the model maps nothing of (other sentences, vendors' own lines). */
  ignored?: number;
  /** Of missing: mapped fields of sentences that say they have no fix (docs/sensors.md, "Validity"). */
  no_fix?: number;
}

/** The plan as one JSON object (docs/planning.md, "Plan JSON"). Producer: metamodel/src/modd_plan/planjson.py (`modd plan --json`, the backend's live plan). Consumers: the backend, the workbench's plan panel (frontend/src/core/plan.ts), the SubBroker's CONFIG builder. Periods and delays are exact decimal strings, wire periods integer microseconds. */
export interface PlanDocument {
  /** Length of the schedule's hyperperiod. */
  hyperperiod_s: DecimalString;
  /** DATA frames per hyperperiod. */
  messages_per_hyperperiod: number;
  /** Topics in id order. */
  topics: PlanTopic[];
  /** Planned streams in id order (sent and derived). */
  streams: PlanStream[];
  /** Each subscription's stream key. */
  subscriptions: Record<string, string>;
  /** Buffer size per topic. */
  buffer_sizes: Record<string, number>;
  schedule: PlanSchedule;
  /** Worst delivery delay per subscription, seconds. */
  delays: Record<string, DecimalString>;
  /** The largest deviation of the buffers. */
  max_delay_s: DecimalString;
  /** The link-cost estimate, as the status carries it. */
  predicted_link_bytes_per_s: PredictedLink;
  /** The declared transport's link budget (modd_plan.linkbudget), else null. */
  link_budget: PlanLinkBudget | null;
  /** Only when the model declares link.radio: the radio's air time, duty cycle and energy per hour (modd_plan.radio), and the nearest plans that fit when it refuses the plan (modd_plan.proposals). */
  radio?: PlanRadio;
  /** Subscriptions the planner could not serve. */
  infeasible: PlanInfeasible[];
  /** True when no buffer sizes meet the delay cap. */
  violates_delay_cap: boolean;
  /** The planner constants in force (decimal strings). */
  constants: object;
}

/** An exact decimal number written as a string. */
export type DecimalString = string;

export interface PlanTopic {
  id: number;
  name: string;
  type: string;
  unit: string;
  publication_period_s: DecimalString | null;
  period_us: number | null;
  buffer_size: number | null;
}

export interface PlanSource {
  key: string;
  factor: number;
}

export interface PlanStream {
  /** The wire id of a sent stream; null for a derived one. */
  id: number | null;
  /** topic/AGGREGATION/period_s */
  key: string;
  topic: string;
  aggregation: string;
  period_s: DecimalString;
  period_us: number;
  /** Sent over the link (else derived at the SubBroker). */
  sent: boolean;
  derived_from: string | null;
  factor: number;
  sources: PlanSource[];
  subscribers: string[];
  /** An event stream's (ON_CHANGE, THRESHOLD) worst case: events a window at most, its declared maxEvents or every sample of the window; absent for the others. */
  events_at_most?: number;
  /** An event stream's value bytes a second at most, every window at its worst case (the plan's link figures count it so); absent for the others. */
  bytes_per_s_at_most?: number;
}

export interface PlanSlot {
  slot: number;
  date_s: DecimalString;
  streams: number[];
}

export interface PlanSentStream {
  id: number;
  key: string;
  period_us: number;
}

/** The slot table (the first slots of the hyperperiod, bounded). */
export interface PlanSchedule {
  epoch_phase_s: DecimalString;
  streams: PlanSentStream[];
  slots: PlanSlot[];
  slots_listed: number;
  slots_truncated: boolean;
}

/** The declared transport's link budget (metamodel/src/modd_plan/linkbudget.py). */
export interface PlanLinkBudget {
  transport: "tcp" | "udp" | "serial";
  rate_bps: number | null;
  max_packet: number;
  accepted_delay_s: number;
  drone_to_base: number;
  base_to_drone: number;
  packets_per_s: number;
  share: number | null;
  delays_s: Record<string, number>;
  over_budget: string[];
  error: string | null;
  control?: PlanLinkControl;
}

/** The declared radio's figures per hour of the plan (metamodel/src/modd_plan/radio.py). */
export interface PlanRadio {
  kind: "sik" | "wifi" | "lora";
  bytes_per_s: number;
  packets_per_hour: number;
  air_time_s_per_hour: number;
  /** The duty-cycle limit (0.01: 1 %), else null. */
  duty_cycle: number | null;
  /** Air time (the bound's, when there is one) over the limit's (above 1: refused), else null. */
  duty_share: number | null;
  /** What the air-time and energy figures are: exact (nothing quantised), upper_bound (every quantised value sized at its declared range) or estimate (quantised deltas assumed small, or the link's control traffic counted: its STATUS sizes vary; docs/planning.md, "Bounds and estimates"). */
  figures?: "exact" | "upper_bound" | "estimate";
  /** With estimated figures: the air time of the bound the duty-cycle check uses (duty_share is its share): the DATA's bound with the control traffic's (the link budget's control.bound_bytes_per_s), else null. */
  air_time_bound_s_per_hour?: number | null;
  /** Only in a plan calibrated by an archive (modd plan --calibrate): its name; the quantised values were sized from its samples (figures: estimate). */
  calibrated_from?: string;
  calibration?: PlanCalibration;
  energy_j_per_hour: number;
  battery_wh: number | null;
  battery_share_per_hour: number | null;
  costs: PlanRadioCost[];
  /** Why the plan is refused (over the duty-cycle limit), else null. */
  error: string | null;
  /** The refusal located in the model: the duty-cycle limit and the subscriptions that cost most. */
  diagnostics: PlanRadioDiagnostic[];
  proposals: PlanProposal[];
}

export interface PlanRadioCost {
  subscription: string;
  bytes_per_s: number;
  air_time_s_per_hour: number;
}

export interface PlanRadioDiagnostic {
  /** JSON pointer into the model. */
  pointer: string;
  message: string;
}

/** A nearer plan that fits, verified by planning it again (metamodel/src/modd_plan/proposals.py). */
export interface PlanProposal {
  accepted_delay_s: number;
  /** Every subscription period shorter than this raised to it (s), else null. */
  min_period_s: number | null;
  max_delay_s: number;
  bytes_per_s: number;
  air_time_s_per_hour: number;
  /** Air time (the bound's, when there is one) over the duty-cycle limit's. */
  duty_share: number;
  energy_j_per_hour: number;
  change: string;
  /** What the air-time and energy figures are: exact (nothing quantised), upper_bound (every quantised value sized at its declared range) or estimate (quantised deltas assumed small, or the link's control traffic counted: its STATUS sizes vary; docs/planning.md, "Bounds and estimates"). */
  figures?: "exact" | "upper_bound" | "estimate";
  /** With estimated figures: the air time of the bound the duty-cycle check uses (duty_share is its share): the DATA's bound with the control traffic's (the link budget's control.bound_bytes_per_s), else null. */
  air_time_bound_s_per_hour?: number | null;
  /** Only when the plan is calibrated: the archive the proposal's figures were sized from. */
  calibrated_from?: string;
}

/** The link's own control traffic, drone to base (metamodel/src/modd_plan/control.py): STATUS every status_period_s and a PONG per keepalive PING; bytes_per_s and packets_per_s are estimates, already in drone_to_base and packets_per_s; bound_bytes_per_s is at most (a STATUS of the whole STATUS room each period) while the instruments' states hold. */
export interface PlanLinkControl {
  status_period_s: number;
  bytes_per_s: number;
  packets_per_s: number;
  bound_bytes_per_s: number;
}

/** What an archive gave a calibrated plan (metamodel/src/modd_plan/calibration.py): the mean bytes of each quantised stream's values measured on its first windows, and the quantised streams it has no sample of (sized as without a calibration). */
export interface PlanCalibration {
  /** Windows of each stream recomputed at most (the archive's first). */
  windows_limit: number;
  streams: PlanCalibratedStream[];
  /** Keys of the quantised streams whose topic the archive does not hold. */
  not_calibrated: string[];
}

export interface PlanCalibratedStream {
  /** The sent stream's key. */
  stream: string;
  /** Mean bytes of its first value in a unit (absolute steps). */
  absolute_bytes: number;
  /** Mean bytes of a later value (a delta of steps). */
  delta_bytes: number;
  /** Windows measured. */
  windows: number;
}

export interface PlanInfeasible {
  topic: string;
  subscribers: string[];
  reason: string;
}

/** The PubBroker's configuration file, pubbroker.json (docs/pubbroker.md). Producer: generators/src/modd_gen/targets/pubbroker_config.py (operator/pubbroker.json), `modd up`. Consumer: runtime/cpp/src/broker/config.cpp, which refuses unknown keys. Each `default` is what the PubBroker uses when the key is absent (config.hpp; a test holds the two together) and what the generator writes. */
export interface PubBrokerConfig {
  /** The drone's name. */
  name?: string;
  link: PubBrokerLink;
  ingress?: PubBrokerIngress;
  archive: PubBrokerArchive;
  /** Topics known before the first CONFIG. */
  topics?: PubBrokerTopic[];
  /** Buffer size of a topic the plan does not size. */
  default_buffer_size?: number;
  /** Archive topics no configuration names. */
  accept_unknown_topics?: boolean;
  /** STATUS frame period until a CONFIG sets it. */
  status_period_s?: number;
  /** Period of the counters line in the log. */
  log_period_s?: number;
  log?: PubBrokerLog;
}

/** Where the PubBroker listens for the SubBroker, and the link key. */
export interface PubBrokerLink {
  host?: string;
  port?: number;
  /** The link key's reference, env:NAME or file:PATH. */
  key: string;
  handshake_timeout_ms?: number;
}

/** Local ingress (docs/ingress.md): a Unix socket and/or TCP. */
export interface PubBrokerIngress {
  unix_path?: string;
  host?: string;
  /** 0: no TCP ingress. */
  port?: number;
  max_future_ms?: number;
  max_past_ms?: number;
  /** 0: no quota. */
  publisher_quota_samples?: number;
  /** 0: no quota. */
  topic_quota_samples?: number;
}

/** The MCAP archive (docs/pubbroker.md, "Archive"). */
export interface PubBrokerArchive {
  dir: string;
  prefix?: string;
  rotate_bytes?: number;
  rotate_s?: number;
  fsync?: "never" | "chunk" | "close";
  compression?: "zstd" | "lz4" | "none";
  chunk_bytes?: number;
  flush_interval_ms?: number;
  queue_limit_samples?: number;
  message_index?: boolean;
  low_space_mb?: number;
  retry_max_ms?: number;
}

export interface PubBrokerTopic {
  name: string;
  type?: "float32" | "float64" | "int" | "bool";
  /** 0: default_buffer_size. */
  buffer_size?: number;
}

export interface PubBrokerLog {
  file?: string;
  max_bytes?: number;
  keep?: number;
}

/** One sample in the PubBroker's MCAP archive: the data of one MCAP Message, on the channel of its topic (channel topic = the topic's name, message encoding json, channel metadata {"type": <value type>}), whose MCAP Schema is named modd.<value type> with encoding jsonschema and the data given in x-channel-schemas; the message's log time is the sample's time (ns since the Unix epoch on the drone's clock). Written compact, exactly as the vectors show ({"value":1.5}). A non-finite float is written as the bare word nan, inf or -inf (what std::to_chars gives; not JSON): readers accept those three words in place of a number. Producer: runtime/cpp/src/archive/archiver.cpp (format_sample_json, sample_json_schema via archive_record.gen.hpp). Consumers: runtime/cpp/src/archive/reader.cpp (backfill), backend archives.py, modd dataset (runtime/python/src/modd/dataset/mcapread.py). Vectors: contracts/vectors/archive_record.json. */
export interface ArchiveRecord {
  /** The sample: a number for float32, float64 and int topics (an integer for int), a boolean for bool topics. */
  value: number | boolean;
}

/** A backfill job's progress document, the answer of the SubBroker's modd/<drone>/backfill queryable to start, progress, cap and cancel (or an error with its reason). Producer: runtime/python/src/modd/subbroker/backfill_queue.py (progress), backfill_query.py. Consumers: the backend (routers/backfill.py, relayed as is), `modd backfill`, the workbench's Fill gaps. docs/subbroker.md, "Backfill". A new field is added here first. */
export interface BackfillProgress {
  /** RUNNING, DONE, CANCELLED, FAILED; or UNKNOWN, ERROR, UNAUTHORISED (the queryable), NO_REPLY (the backend). */
  status: string;
  /** What a running job waits for, in words ("queued behind 3 jobs", "paced at 600 B/s"), or why it ended or was refused. */
  reason?: string | null;
  /** The job's id. */
  id?: number | null;
  /** The subscription filled. */
  subscriber?: string | null;
  /** Windows delivered to the subscriber. */
  windows?: number;
  /** Windows received from the drone (delivered or already there). */
  windows_done?: number;
  /** Windows the job asks for. */
  windows_total?: number;
  /** Windows received that had been delivered already (not delivered again). */
  duplicates?: number;
  /** Link bytes of the job's BACKFILL_DATA frames. */
  bytes?: number;
  /** The job's pace in bytes/s (0: the PubBroker's own). */
  rate_bps?: number;
  /** Seconds since the job started (until it ended). */
  seconds?: number;
  /** The job's bytes over its seconds. */
  bytes_per_s?: number;
  /** Seconds until the job is done, from the queue's view (the job and a fair share of the others at the measured pace); null where that cannot be computed (the queue's states say why). */
  seconds_left?: number | null;
  /** Link requests sent for the job. */
  requests?: number;
  /** Requests sent again after a loss, a silence or a BUSY. */
  resumes?: number;
  /** Start of the range filled (answer to start). */
  from_ns?: number;
  /** End of the range filled (answer to start). */
  to_ns?: number;
  /** The SubBroker's backfill queue as it stands (a running job only; null or absent otherwise). */
  queue?: BackfillQueue | null;
}

/** The jobs that have not ended, in the order the queue serves them (the one on the link first), at most 32; the link's measured backfill pace. */
export interface BackfillQueue {
  /** The jobs, the one on the link first. */
  jobs: BackfillQueueJob[];
  /** Jobs past the ones listed. */
  more: number;
  /** Bytes/s between the backfill frames of the last seconds, the drone's pauses for its archive left out; null until measured. */
  pace_bps: number | null;
  /** Mean seconds from a run's request to its first frame (the last 16 runs); null until measured. */
  trip_s: number | null;
}

/** One job of the queue. */
export interface BackfillQueueJob {
  /** The job's id. */
  id: number;
  state: BackfillJobState;
  /** Windows received. */
  windows_done: number;
  /** Windows asked. */
  windows_total: number;
  /** Link requests left (the one on the link included). */
  runs_left: number;
  /** Seconds the job's rest takes on the link alone at the measured pace; null until the pace and the bytes of its windows are measured. */
  send_s: number | null;
}

/** What a job waits for: sending (its frames come), asking (its request is on the way), unanswered (asked again, no answer yet), waiting_archive (acknowledged, silent: the drone waits for its archive to hold the windows), waiting_link, busy (the PubBroker said BUSY), queued (behind the job on the link). */
export type BackfillJobState = "sending" | "asking" | "unanswered" | "waiting_archive" | "waiting_link" | "busy" | "queued";
export const BackfillJobStateValues = ["sending", "asking", "unanswered", "waiting_archive", "waiting_link", "busy", "queued"] as const;

/** The aggregation table (modd.schema.json Aggregation x-table). */
export const AGGREGATION_TABLE = [
  { name: "MIN", code: 0, numericOnly: false },
  { name: "MAX", code: 1, numericOnly: false },
  { name: "AVERAGE", code: 2, numericOnly: true },
  { name: "FIRST", code: 3, numericOnly: false },
  { name: "LAST", code: 4, numericOnly: false },
  { name: "ALL", code: 5, numericOnly: false },
  { name: "COUNT", code: 6, numericOnly: false },
  { name: "SUM", code: 7, numericOnly: true },
  { name: "MEDIAN", code: 8, numericOnly: true },
  { name: "STDDEV", code: 9, numericOnly: true },
  { name: "RANGE", code: 10, numericOnly: true },
  { name: "PERCENTILE", code: 11, numericOnly: true },
  { name: "ON_CHANGE", code: 12, numericOnly: false },
  { name: "THRESHOLD", code: 13, numericOnly: true },
] as const;

/** Each aggregation's name, for code that compares or builds one. */
export const AGGREGATION = {
  MIN: "MIN",
  MAX: "MAX",
  AVERAGE: "AVERAGE",
  FIRST: "FIRST",
  LAST: "LAST",
  ALL: "ALL",
  COUNT: "COUNT",
  SUM: "SUM",
  MEDIAN: "MEDIAN",
  STDDEV: "STDDEV",
  RANGE: "RANGE",
  PERCENTILE: "PERCENTILE",
  ON_CHANGE: "ON_CHANGE",
  THRESHOLD: "THRESHOLD",
} as const;

/** The role owning each model part (modd.schema.json x-owner; null: any editor). */
export const MODEL_PART_OWNERS: Readonly<Record<string, "designer" | "integrator" | "scientist" | null>> = {
  "/schemaVersion": "designer",
  "/drone": "designer",
  "/drone/sensors": "integrator",
  "/pubBroker": "designer",
  "/subBroker": "designer",
  "/link": "designer",
  "/publishers": "designer",
  "/subscribers": "scientist",
  "/campaign": "designer",
  "/layout": null,
};
