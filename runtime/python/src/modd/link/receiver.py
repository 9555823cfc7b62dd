"""Base-station side of DATA: turns frames into per-stream window values.

The receiver knows each CONFIG it sent and the epoch its CONFIG_ACK gave, extends the
8-bit slot sequence (TCP is ordered; after any gap the broker sends a sync frame with the
full slot number), and labels every value with its window [start, end) in broker ns.

Example::

    rx = Receiver()
    rx.add_config(config, ack.epoch_ns)
    for window in rx.on_frame(raw):   # raw: a DATA RawFrame
        print(window.stream, window.start_ns, window.value)
"""

from __future__ import annotations

from dataclasses import dataclass

from modd.link import codec
from modd.link.frames import Config, ErrorCode, ProtocolError, Value, ValueKind
from modd.link.schedule import SlotIterator


@dataclass(frozen=True)
class Window:
    config_id: int
    slot: int
    stream: int  # stream id in the config
    start_ns: int
    end_ns: int
    value: Value


@dataclass
class _Running:
    config: Config
    epoch_ns: int
    kinds: list[ValueKind]
    slots: SlotIterator
    next_slot: int = 0


class Receiver:
    def __init__(self) -> None:
        self._configs: dict[int, _Running] = {}
        self._current: _Running | None = None

    def add_config(self, config: Config, epoch_ns: int) -> None:
        """Registers a CONFIG the broker acknowledged (or reported in AUTH_OK) and its epoch."""
        periods = [s.period_us for s in config.streams]
        self._configs[config.config_id] = _Running(
            config, epoch_ns, config.kinds(), SlotIterator(periods)
        )

    def on_frame(self, f: codec.RawFrame) -> list[Window]:
        h = codec.decode_data_header(f)
        if h.sync:
            run = self._configs.get(h.config_id)
            if run is None:
                raise ProtocolError(ErrorCode.BAD_CONFIG, f"DATA for unknown config {h.config_id}")
            self._current = run
            if h.slot < run.next_slot:
                raise ProtocolError(ErrorCode.BAD_FRAME, f"slot {h.slot} goes backwards")
            run.slots.skip_to(h.slot)
            run.next_slot = h.slot
        else:
            run = self._current
            if run is None:
                raise ProtocolError(ErrorCode.BAD_FRAME, "DATA before any sync frame")
            if (run.next_slot & 0xFF) != h.seq8:
                raise ProtocolError(
                    ErrorCode.BAD_FRAME, f"slot sequence {h.seq8}, expected {run.next_slot & 0xFF}"
                )
        slot = next(run.slots)
        run.next_slot = slot.index + 1
        kinds = [run.kinds[s] for s in slot.streams]
        data = codec.decode_data(f, kinds)
        end = run.epoch_ns + slot.offset_us * 1000
        out = []
        for sid, v in zip(slot.streams, data.values, strict=True):
            start = end - run.config.streams[sid].period_us * 1000
            out.append(Window(run.config.config_id, slot.index, sid, start, end, v))
        return out
