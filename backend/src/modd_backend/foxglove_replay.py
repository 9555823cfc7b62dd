"""Ranged playback of a recorded mission in Foxglove or Lichtblick (seek,
play, pause, speed) through a ``foxglove-sdk`` server with the
``PlaybackControl`` capability.

What it plays: MCAP files — the PubBroker's archive of a mission (one JSON
channel per topic, every raw sample), a file recovered with ``modd archive
recover``, or any MCAP file with JSON channels. Channels keep their topic
names, schemas and ``log_time``.

    modd-foxglove-replay data/run/archive/usv/*.mcap --port 8766

Contract: one player thread emits the messages whose log time the playback
clock has passed, at the requested speed; a seek moves the clock and the
cursor (binary search), a pause stops the clock; every request is answered
with a ``PlaybackState`` carrying its request id.
"""

from __future__ import annotations

import argparse
import bisect
import json
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .viewer_json import as_numbers, delivered_schema, without_nulls

if TYPE_CHECKING:
    from .loopback_tls import LoopbackTls

#: Messages kept in memory at most (a mission day at 100 Hz on 50 topics).
MAX_MESSAGES = 5_000_000
#: Autoplay starts this long after a viewer's last new subscription when it
#: has not subscribed to every channel (a viewer subscribes to what its panels
#: show): its subscriptions arrive one by one, over a few hundred ms.
AUTOPLAY_SETTLE_S = 0.5


@dataclass(frozen=True)
class Recorded:
    log_time: int
    topic: str
    data: bytes


@dataclass(frozen=True)
class RecordedChannel:
    topic: str
    encoding: str
    schema_name: str
    schema_encoding: str
    schema: bytes


def load_recording(
    paths: Sequence[Path],
    max_messages: int = MAX_MESSAGES,
    *,
    partial: bool = False,
    start_ns: int | None = None,
    end_ns: int | None = None,
    time_s: float | None = None,
) -> tuple[dict[str, RecordedChannel], list[Recorded]]:
    """Channels and messages (sorted by log time) of MCAP files, those whose
    log time is in [start_ns, end_ns). A file without a summary (still being
    written, or cut by a crash) is refused unless ``partial``: then its
    complete records are played, up to the cut. Reading longer than
    ``time_s`` is refused (ValueError), as is more than ``max_messages``."""
    from mcap.reader import make_reader

    channels: dict[str, RecordedChannel] = {}
    messages: list[Recorded] = []
    deadline = None if time_s is None else time.monotonic() + time_s

    def keep(topic: str, schema: Any, encoding: str, log_time: int, data: bytes) -> None:
        if (start_ns is not None and log_time < start_ns) or (
            end_ns is not None and log_time >= end_ns
        ):
            return
        if topic not in channels:
            channels[topic] = RecordedChannel(
                topic,
                encoding,
                schema.name if schema else "",
                schema.encoding if schema else "",
                schema.data if schema else b"",
            )
        messages.append(Recorded(log_time, topic, data))
        if deadline is not None and not len(messages) % 4096 and time.monotonic() > deadline:
            raise ValueError(
                f"more than {time_s:g} s of reading messages to play: choose a shorter time range"
            )
        if len(messages) > max_messages:
            raise ValueError(
                f"more than {max_messages} messages to play: choose a shorter time range"
            )

    for path in paths:
        first = len(messages)  # a fallback to the partial reader starts this file again
        with open(path, "rb") as f:
            try:
                reader = make_reader(f)
                if partial and reader.get_summary() is None:
                    raise EOFError("no summary")
                for schema, ch, m in reader.iter_messages(
                    starting_at=start_ns, ending_before=end_ns
                ):
                    keep(ch.topic, schema, ch.message_encoding, m.log_time, m.data)
            except ValueError as exc:
                if "messages to play" in str(exc):
                    raise ValueError(f"{path}: {exc}") from None
                if not partial:
                    raise ValueError(
                        f"{path}: cannot be read ({exc}); if a crash cut it, run "
                        "`modd archive recover` first"
                    ) from None
                del messages[first:]
                _load_partial(path, keep)
            except Exception as exc:  # the reader's errors have no common base
                if not partial:
                    raise ValueError(
                        f"{path}: cannot be read ({exc}); if a crash cut it, run "
                        "`modd archive recover` first"
                    ) from None
                del messages[first:]
                _load_partial(path, keep)
    if not messages:
        raise ValueError("nothing to play: the files hold no message in that range")
    messages.sort(key=lambda r: r.log_time)
    return _delivered_for_viewers(channels, messages)


#: The schema name of the base-station record's channels (modd.subbroker.record).
DELIVERED = "modd.DeliveredValue"


def _delivered_for_viewers(
    channels: dict[str, RecordedChannel], messages: list[Recorded]
) -> tuple[dict[str, RecordedChannel], list[Recorded]]:
    """A base-station record's windows as the live server sends them: every
    message valid against its channel's schema (the delivered-value contract
    with one type per field; a null left out, a boolean as 1/0), each with its
    historical mark ``backfilled`` (false for a live one, which the record
    leaves out). The record itself keeps the delivered bytes."""
    record = {t for t, c in channels.items() if c.schema_name == DELIVERED}
    if not record:
        return channels, messages
    aggregation: dict[str, str] = {}
    out: list[Recorded] = []
    for m in messages:
        if m.topic not in record:
            out.append(m)
            continue
        try:
            doc = json.loads(m.data)
        except (ValueError, UnicodeDecodeError):
            continue  # not a delivered value: nothing a viewer could read
        if not isinstance(doc, dict):
            continue
        aggregation.setdefault(m.topic, str(doc.get("aggregation", "")))
        doc["value"] = as_numbers(doc.get("value"))
        doc["backfilled"] = doc.get("backfilled") is True  # live ones marked too: a plottable 0/1
        out.append(Recorded(m.log_time, m.topic, json.dumps(without_nulls(doc)).encode()))
    for topic in record:
        schema = json.dumps(delivered_schema(aggregation.get(topic, ""))).encode()
        channels[topic] = replace(channels[topic], schema=schema)
    return channels, out


def _load_partial(path: Path, keep: Any) -> None:
    """The complete records of a file without a summary, in file order,
    stopping quietly where it is cut (the file being written ends there)."""
    import struct

    from mcap.exceptions import McapError
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    with open(path, "rb") as f:
        try:
            for rec in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                if isinstance(rec, Schema):
                    schemas[rec.id] = rec
                elif isinstance(rec, Channel):
                    channels[rec.id] = rec
                elif isinstance(rec, Message) and rec.channel_id in channels:
                    ch = channels[rec.channel_id]
                    keep(
                        ch.topic,
                        schemas.get(ch.schema_id),
                        ch.message_encoding,
                        rec.log_time,
                        rec.data,
                    )
        except (McapError, EOFError, OSError, struct.error):
            return
        except ValueError as exc:
            if "messages to play" in str(exc):
                raise
            return


class Player:
    """The playback clock and cursor over ``messages``; thread-safe."""

    def __init__(self, messages: list[Recorded]) -> None:
        self.messages = messages
        self._times = [m.log_time for m in messages]
        self.start, self.end = self._times[0], self._times[-1]
        self.current = self.start
        self.speed = 1.0
        self.playing = False
        self._cursor = 0
        self._lock = threading.Lock()

    def seek(self, t: int) -> None:
        with self._lock:
            self.current = min(max(t, self.start), self.end)
            self._cursor = bisect.bisect_left(self._times, self.current)

    def control(self, play: bool, speed: float, seek_time: int | None) -> None:
        if seek_time is not None:
            self.seek(seek_time)
        with self._lock:
            self.playing = play
            if speed > 0:
                self.speed = speed

    def advance(self, elapsed_s: float) -> list[Recorded]:
        """Moves the clock by ``elapsed_s`` (when playing); the messages passed."""
        with self._lock:
            if not self.playing:
                return []
            self.current = min(self.end, self.current + int(elapsed_s * self.speed * 1e9))
            stop = bisect.bisect_right(self._times, self.current)
            out = self.messages[self._cursor : stop]
            self._cursor = stop
            if self.current >= self.end:
                self.playing = False
            return out

    @property
    def ended(self) -> bool:
        return self.current >= self.end


class ReplayServer:
    """A ranged-playback Foxglove server over a recording, on ``host:port``;
    with ``tls``, it speaks ``wss://`` only (the backend's replay slot, reached
    through its proxy: loopback_tls.py)."""

    def __init__(
        self,
        paths: Sequence[Path],
        host: str = "127.0.0.1",
        port: int = 8766,
        tick_s: float = 0.02,
        *,
        recording: tuple[dict[str, RecordedChannel], list[Recorded]] | None = None,
        autoplay: bool = False,
        tls: LoopbackTls | None = None,
    ) -> None:
        import foxglove
        from foxglove.websocket import Capability, ServerListener

        channels, messages = recording if recording is not None else load_recording(paths)
        self.player = Player(messages)
        # Lichtblick's WebSocket player (1.28) has no playback controls: it
        # subscribes and waits. With autoplay the range plays once from its
        # start when the viewer has subscribed (every channel, or no new one
        # for AUTOPLAY_SETTLE_S), unless a client has already taken control:
        # starting on the first subscription lost the start of the channels
        # subscribed after it (0.24-0.40 s of 8 of 11 channels).
        self.autoplay = autoplay
        self._controlled = False
        self._subscribed: set[str] = set()
        self._autoplay_at: float | None = None  # monotonic time autoplay starts
        self.context = foxglove.Context()
        self.channels = {
            t: foxglove.Channel(
                t,
                message_encoding=c.encoding or "json",
                context=self.context,
                schema=foxglove.Schema(
                    name=c.schema_name or t,
                    encoding=c.schema_encoding or "jsonschema",
                    data=c.schema,
                ),
            )
            for t, c in channels.items()
        }
        replay = self

        class Listener(ServerListener):
            def on_playback_control_request(self, request: Any) -> Any:
                return replay.on_request(request)

            def on_subscribe(self, client: Any, channel: Any) -> None:
                replay.on_subscribe(str(channel.topic))

        self.server = foxglove.start_server(
            name="MoDD replay",
            host=host,
            port=port,
            context=self.context,
            capabilities=[Capability.PlaybackControl, Capability.Time],
            server_listener=Listener(),
            playback_time_range=(self.player.start, self.player.end),
            tls_cert=tls.cert_pem if tls else None,
            tls_key=tls.key_pem if tls else None,
        )
        self.port = self.server.port
        self.host = host
        self._tick = tick_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="modd-replay", daemon=True)
        self._thread.start()

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    def state(self, request_id: str | None, did_seek: bool) -> Any:
        from foxglove.websocket import PlaybackState, PlaybackStatus

        p = self.player
        status = (
            PlaybackStatus.Ended
            if p.ended
            else PlaybackStatus.Playing
            if p.playing
            else PlaybackStatus.Paused
        )
        return PlaybackState(
            status=status,
            current_time=p.current,
            playback_speed=p.speed,
            did_seek=did_seek,
            request_id=request_id,
        )

    def on_subscribe(self, topic: str) -> None:
        if not self.autoplay or self._controlled:
            return  # later subscriptions join the running playback
        self._subscribed.add(topic)
        every = self._subscribed >= set(self.channels)
        self._autoplay_at = time.monotonic() + (0.0 if every else AUTOPLAY_SETTLE_S)

    def _autoplay(self, now: float) -> None:
        """Starts the autoplay when its time has come (the player thread)."""
        at = self._autoplay_at
        if at is not None and now >= at and not self._controlled:
            self._controlled = True  # once
            self._autoplay_at = None
            self.player.control(True, self.player.speed, None)

    def on_request(self, request: Any) -> Any:
        from foxglove.websocket import PlaybackCommand

        self._controlled = True
        self._autoplay_at = None
        self.player.control(
            request.playback_command == PlaybackCommand.Play,
            float(request.playback_speed),
            request.seek_time,
        )
        return self.state(request.request_id, request.seek_time is not None)

    def _run(self) -> None:
        last = time.monotonic()
        was_playing = False
        while not self._stop.wait(self._tick):
            now = time.monotonic()
            for m in self.player.advance(now - last):
                self.channels[m.topic].log(m.data, log_time=m.log_time)
            last = now
            self._autoplay(now)
            if self.player.playing and not was_playing:
                self.server.broadcast_playback_state(self.state(None, False))  # autoplay began
            if self.player.playing or was_playing:
                self.server.broadcast_time(self.player.current)
            if was_playing and not self.player.playing:
                self.server.broadcast_playback_state(self.state(None, False))
            was_playing = self.player.playing

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2)
        for ch in self.channels.values():
            ch.close()
        self.server.stop()


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="modd-foxglove-replay",
        description="Ranged playback of MCAP files for Foxglove/Lichtblick",
    )
    p.add_argument("files", nargs="+", type=Path, metavar="FILE")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default loopback)")
    p.add_argument("--port", type=int, default=8766)
    p.add_argument(
        "--autoplay",
        action="store_true",
        help="play once from the start when a viewer subscribes (for viewers "
        "without playback controls, such as Lichtblick)",
    )
    a = p.parse_args(argv)
    try:
        server = ReplayServer(a.files, a.host, a.port, autoplay=a.autoplay)
    except (ValueError, OSError) as exc:
        print(f"modd-foxglove-replay: {exc}")
        return 1
    print(
        f"modd-foxglove-replay: {server.url} plays {len(server.player.messages)} messages "
        f"on {len(server.channels)} channels (Ctrl-C to stop)",
        flush=True,
    )
    try:
        threading.Event().wait()
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
