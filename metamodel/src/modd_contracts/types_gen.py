"""Generated from the contracts by `python -m modd_contracts.typegen`. Do not edit."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, NotRequired, TypedDict

DELIVERED_VALUE_VERSION = 1
STATUS_VERSION = 1
PLAN_VERSION = 1
PUBBROKER_VERSION = 1
ARCHIVE_RECORD_VERSION = 1
BACKFILL_VERSION = 1


LinkState = Literal["connecting", "handshake", "configuring", "up", "down", "stopped"]
DecimalString = str
BackfillJobState = Literal["sending", "asking", "unanswered", "waiting_archive", "waiting_link", "busy", "queued"]


class DeliveredValue(TypedDict):
    """One window of one subscription, as the SubBroker puts it on modd/<drone>/sub/<subscriber> and writes it on a TCP delivery connection (one compact JSON object a line)."""

    subscriber: str
    topic: str
    aggregation: str
    period_s: str
    unit: str
    config_id: int
    slot: int
    start_ns: int
    end_ns: int
    value: float | bool | Literal["Infinity", "-Infinity", "NaN"] | list[float | bool | Literal["Infinity", "-Infinity", "NaN"]] | None
    count: int | None
    delivered_ns: int
    v: int
    backfilled: NotRequired[bool]
    drone: NotRequired[str]
    epoch_ns: NotRequired[int]
    window: NotRequired[int]
    event_ns: NotRequired[list[int]]
    coalesced: NotRequired[int]


class SubBrokerStatus(TypedDict):
    """The SubBroker's status document, put on modd/<drone>/status every status_period_s."""

    drone: str
    time_ns: int
    link: LinkState
    endpoint: str
    rtt_s: float | None
    config_id: int | None
    epoch_ns: int | None
    bytes_in: int
    bytes_out: int
    data_frames: int
    skipped_frames: int
    connects: int
    last_data_ns: int | None
    last_error: str | None
    delivered: int
    state_files_set_aside: NotRequired[list[Any]]
    predicted_link_bytes_per_s: PredictedLink | None
    routes: dict[str, list[str]]
    dynamic: list[str]
    tcp: dict[str, TcpSender]
    pubbroker: dict[str, int]
    bytes_in_per_s: NotRequired[float | None]
    bytes_out_per_s: NotRequired[float | None]
    ip_bytes_in_per_s: NotRequired[float | None]
    behind: NotRequired[bool]
    lag_s: NotRequired[float | None]
    max_lag_s: NotRequired[float]
    recv_backlog_bytes: NotRequired[int]
    behind_since_ns: NotRequired[int | None]
    behind_episodes: NotRequired[int]
    deployment: NotRequired[Any]
    station: NotRequired[str]
    transport: NotRequired[str]
    link_budget: NotRequired[dict[str, Any] | None]
    radio: NotRequired[RadioStatus | None]
    sensors: NotRequired[dict[str, SensorHealth]]
    supervisor: NotRequired[Any]
    onboard: NotRequired[dict[str, dict[str, Any]]]


class RadioStatus(TypedDict):
    """A datagram link's figures (modd.subbroker.dglink.DatagramLinkClient.radio_status): the wire bytes/s per direction over the last 10 s, the share of slots lost or repaired, the datagrams refused, and the PubBroker's own counters from its last STATUS."""

    transport: Literal["udp", "serial"]
    accepted_delay_s: float
    wire_bytes_in_per_s: Any
    wire_bytes_out_per_s: Any
    loss: Any
    slots_received: int
    retransmissions: int
    slots_lost: int
    slots_missing: int
    nacks: int
    datagrams_in: int
    forged: int
    replayed: int
    malformed: int
    unknown_config: int
    handshakes: int
    heard_elsewhere: NotRequired[int]
    heard_elsewhere_used: NotRequired[int]
    pubbroker: PubBrokerDatagrams | None


class PubBrokerDatagrams(TypedDict):
    """What the PubBroker counted on its datagram link."""

    datagrams_sent: int
    datagrams_resent: int
    nacks: int
    slots_dropped: int
    forged: int
    replayed: int


class PredictedLink(TypedDict):
    """The planner's link-cost estimate, bytes per second (modd_plan.linkcost.LinkCost.to_json)."""

    drone_to_base: float
    base_to_drone: float
    plain_pubsub: float
    plain_pubsub_acks: float
    frames_per_s: float
    saving_ratio: float


class TcpSender(TypedDict):
    """One TCP delivery connection."""

    connected: bool
    sent: int
    dropped: int


class SensorHealth(TypedDict):
    """One instrument as modd-sensors counts it since it started; a field a newer modd-sensors appends is kept as field_<i>."""

    state: NotRequired[int]
    lines_ok: NotRequired[int]
    lines_bad: NotRequired[int]
    reconnects: NotRequired[int]
    last_value_ms: NotRequired[int]
    values: NotRequired[int]
    missing: NotRequired[int]
    refused: NotRequired[int]
    timeouts: NotRequired[int]
    exceptions: NotRequired[int]
    silences: NotRequired[int]
    ignored: NotRequired[int]
    no_fix: NotRequired[int]


class PlanDocument(TypedDict):
    """The plan as one JSON object (docs/planning.md, "Plan JSON")."""

    hyperperiod_s: DecimalString
    messages_per_hyperperiod: int
    topics: list[PlanTopic]
    streams: list[PlanStream]
    subscriptions: dict[str, str]
    buffer_sizes: dict[str, int]
    schedule: PlanSchedule
    delays: dict[str, DecimalString]
    max_delay_s: DecimalString
    predicted_link_bytes_per_s: PredictedLink
    link_budget: PlanLinkBudget | None
    radio: NotRequired[PlanRadio]
    infeasible: list[PlanInfeasible]
    violates_delay_cap: bool
    constants: dict[str, Any]


class PlanTopic(TypedDict):
    """PlanTopic."""

    id: int
    name: str
    type: str
    unit: str
    publication_period_s: DecimalString | None
    period_us: int | None
    buffer_size: int | None


class PlanSource(TypedDict):
    """PlanSource."""

    key: str
    factor: int


class PlanStream(TypedDict):
    """PlanStream."""

    id: int | None
    key: str
    topic: str
    aggregation: str
    period_s: DecimalString
    period_us: int
    sent: bool
    derived_from: str | None
    factor: int
    sources: list[PlanSource]
    subscribers: list[str]
    events_at_most: NotRequired[int]
    bytes_per_s_at_most: NotRequired[float]


class PlanSlot(TypedDict):
    """PlanSlot."""

    slot: int
    date_s: DecimalString
    streams: list[int]


class PlanSentStream(TypedDict):
    """PlanSentStream."""

    id: int
    key: str
    period_us: int


class PlanSchedule(TypedDict):
    """The slot table (the first slots of the hyperperiod, bounded)."""

    epoch_phase_s: DecimalString
    streams: list[PlanSentStream]
    slots: list[PlanSlot]
    slots_listed: int
    slots_truncated: bool


class PlanLinkBudget(TypedDict):
    """The declared transport's link budget (metamodel/src/modd_plan/linkbudget.py)."""

    transport: Literal["tcp", "udp", "serial"]
    rate_bps: float | None
    max_packet: int
    accepted_delay_s: float
    drone_to_base: float
    base_to_drone: float
    packets_per_s: float
    share: float | None
    delays_s: dict[str, float]
    over_budget: list[str]
    error: str | None
    control: NotRequired[PlanLinkControl]


class PlanRadio(TypedDict):
    """The declared radio's figures per hour of the plan (metamodel/src/modd_plan/radio.py)."""

    kind: Literal["sik", "wifi", "lora"]
    bytes_per_s: float
    packets_per_hour: float
    air_time_s_per_hour: float
    duty_cycle: float | None
    duty_share: float | None
    figures: NotRequired[Literal["exact", "upper_bound", "estimate"]]
    air_time_bound_s_per_hour: NotRequired[float | None]
    calibrated_from: NotRequired[str]
    calibration: NotRequired[PlanCalibration]
    energy_j_per_hour: float
    battery_wh: float | None
    battery_share_per_hour: float | None
    costs: list[PlanRadioCost]
    error: str | None
    diagnostics: list[PlanRadioDiagnostic]
    proposals: list[PlanProposal]


class PlanRadioCost(TypedDict):
    """PlanRadioCost."""

    subscription: str
    bytes_per_s: float
    air_time_s_per_hour: float


class PlanRadioDiagnostic(TypedDict):
    """PlanRadioDiagnostic."""

    pointer: str
    message: str


class PlanProposal(TypedDict):
    """A nearer plan that fits, verified by planning it again (metamodel/src/modd_plan/proposals.py)."""

    accepted_delay_s: float
    min_period_s: float | None
    max_delay_s: float
    bytes_per_s: float
    air_time_s_per_hour: float
    duty_share: float
    energy_j_per_hour: float
    change: str
    figures: NotRequired[Literal["exact", "upper_bound", "estimate"]]
    air_time_bound_s_per_hour: NotRequired[float | None]
    calibrated_from: NotRequired[str]


class PlanLinkControl(TypedDict):
    """The link's own control traffic, drone to base (metamodel/src/modd_plan/control.py): STATUS every status_period_s and a PONG per keepalive PING; bytes_per_s and packets_per_s are estimates, already in drone_to_base and packets_per_s; bound_bytes_per_s is at most (a STATUS of the whole STATUS room each period) while the instruments' states hold."""

    status_period_s: int
    bytes_per_s: float
    packets_per_s: float
    bound_bytes_per_s: float


class PlanCalibration(TypedDict):
    """What an archive gave a calibrated plan (metamodel/src/modd_plan/calibration.py): the mean bytes of each quantised stream's values measured on its first windows, and the quantised streams it has no sample of (sized as without a calibration)."""

    windows_limit: int
    streams: list[PlanCalibratedStream]
    not_calibrated: list[str]


class PlanCalibratedStream(TypedDict):
    """PlanCalibratedStream."""

    stream: str
    absolute_bytes: float
    delta_bytes: float
    windows: int


class PlanInfeasible(TypedDict):
    """PlanInfeasible."""

    topic: str
    subscribers: list[str]
    reason: str


class PubBrokerConfig(TypedDict):
    """The PubBroker's configuration file, pubbroker.json (docs/pubbroker.md)."""

    name: NotRequired[str]
    link: PubBrokerLink
    ingress: NotRequired[PubBrokerIngress]
    archive: PubBrokerArchive
    topics: NotRequired[list[PubBrokerTopic]]
    default_buffer_size: NotRequired[int]
    accept_unknown_topics: NotRequired[bool]
    status_period_s: NotRequired[int]
    log_period_s: NotRequired[int]
    log: NotRequired[PubBrokerLog]


class PubBrokerLink(TypedDict):
    """Where the PubBroker listens for the SubBroker, and the link key."""

    host: NotRequired[str]
    port: NotRequired[int]
    key: str
    handshake_timeout_ms: NotRequired[int]


class PubBrokerIngress(TypedDict):
    """Local ingress (docs/ingress.md): a Unix socket and/or TCP."""

    unix_path: NotRequired[str]
    host: NotRequired[str]
    port: NotRequired[int]
    max_future_ms: NotRequired[int]
    max_past_ms: NotRequired[int]
    publisher_quota_samples: NotRequired[int]
    topic_quota_samples: NotRequired[int]


class PubBrokerArchive(TypedDict):
    """The MCAP archive (docs/pubbroker.md, "Archive")."""

    dir: str
    prefix: NotRequired[str]
    rotate_bytes: NotRequired[int]
    rotate_s: NotRequired[int]
    fsync: NotRequired[Literal["never", "chunk", "close"]]
    compression: NotRequired[Literal["zstd", "lz4", "none"]]
    chunk_bytes: NotRequired[int]
    flush_interval_ms: NotRequired[int]
    queue_limit_samples: NotRequired[int]
    message_index: NotRequired[bool]
    low_space_mb: NotRequired[int]
    retry_max_ms: NotRequired[int]


class PubBrokerTopic(TypedDict):
    """PubBrokerTopic."""

    name: str
    type: NotRequired[Literal["float32", "float64", "int", "bool"]]
    buffer_size: NotRequired[int]


class PubBrokerLog(TypedDict):
    """PubBrokerLog."""

    file: NotRequired[str]
    max_bytes: NotRequired[int]
    keep: NotRequired[int]


class ArchiveRecord(TypedDict):
    """One sample in the PubBroker's MCAP archive: the data of one MCAP Message, on the channel of its topic (channel topic = the topic's name, message encoding json, channel metadata {"type": <value type>}), whose MCAP Schema is named modd.<value type> with encoding jsonschema and the data given in x-channel-schemas; the message's log time is the sample's time (ns since the Unix epoch on the drone's clock)."""

    value: float | bool


class BackfillProgress(TypedDict):
    """A backfill job's progress document, the answer of the SubBroker's modd/<drone>/backfill queryable to start, progress, cap and cancel (or an error with its reason)."""

    status: str
    reason: NotRequired[str | None]
    id: NotRequired[int | None]
    subscriber: NotRequired[str | None]
    windows: NotRequired[int]
    windows_done: NotRequired[int]
    windows_total: NotRequired[int]
    duplicates: NotRequired[int]
    bytes: NotRequired[int]
    rate_bps: NotRequired[int]
    seconds: NotRequired[float]
    bytes_per_s: NotRequired[float]
    seconds_left: NotRequired[float | None]
    requests: NotRequired[int]
    resumes: NotRequired[int]
    from_ns: NotRequired[int]
    to_ns: NotRequired[int]
    queue: NotRequired[BackfillQueue | None]


class BackfillQueue(TypedDict):
    """The jobs that have not ended, in the order the queue serves them (the one on the link first), at most 32; the link's measured backfill pace."""

    jobs: list[BackfillQueueJob]
    more: int
    pace_bps: float | None
    trip_s: float | None


class BackfillQueueJob(TypedDict):
    """One job of the queue."""

    id: int
    state: BackfillJobState
    windows_done: int
    windows_total: int
    runs_left: int
    send_s: float | None


@dataclass(frozen=True)
class DeliveredValueFields:
    """The fields of :class:`DeliveredValue` but v, as a record."""

    subscriber: str
    topic: str
    aggregation: str
    period_s: str
    unit: str
    config_id: int
    slot: int
    start_ns: int
    end_ns: int
    value: float | bool | Literal["Infinity", "-Infinity", "NaN"] | list[float | bool | Literal["Infinity", "-Infinity", "NaN"]] | None
    count: int | None
    delivered_ns: int
    backfilled: bool = False
    drone: str | None = None
    epoch_ns: int | None = None
    window: int | None = None
    event_ns: list[int] | None = None
    coalesced: int | None = None


#: The fields every :class:`DeliveredValue` carries, in the contract's order.
DELIVERED_VALUE_REQUIRED: tuple[str, ...] = ("subscriber", "topic", "aggregation", "period_s", "unit", "config_id", "slot", "start_ns", "end_ns", "value", "count", "delivered_ns", "v",)


__all__ = ["DELIVERED_VALUE_VERSION", "STATUS_VERSION", "PLAN_VERSION", "PUBBROKER_VERSION", "ARCHIVE_RECORD_VERSION", "BACKFILL_VERSION", "DeliveredValue", "SubBrokerStatus", "RadioStatus", "PubBrokerDatagrams", "LinkState", "PredictedLink", "TcpSender", "SensorHealth", "PlanDocument", "DecimalString", "PlanTopic", "PlanSource", "PlanStream", "PlanSlot", "PlanSentStream", "PlanSchedule", "PlanLinkBudget", "PlanRadio", "PlanRadioCost", "PlanRadioDiagnostic", "PlanProposal", "PlanLinkControl", "PlanCalibration", "PlanCalibratedStream", "PlanInfeasible", "PubBrokerConfig", "PubBrokerLink", "PubBrokerIngress", "PubBrokerArchive", "PubBrokerTopic", "PubBrokerLog", "ArchiveRecord", "BackfillProgress", "BackfillQueue", "BackfillQueueJob", "BackfillJobState", "DeliveredValueFields", "DELIVERED_VALUE_REQUIRED"]
