"""The link session over one byte stream (tcp): frames split from the bytes
read, DATA decoded by the codec's :class:`~modd.link.receiver.Receiver`
(docs/protocol.md, "DATA").

Silence: after half the liveness timeout without a frame it sends one PING;
after the whole timeout the session is over. Nothing else is sent while DATA
flows, so that the link stays as quiet as the plan predicts.

>>> s = StreamSession(b"key", LinkOptions(), handler)   # doctest: +SKIP
>>> s.begin(); s.feed(sock.recv(65536)); s.tick(); s.take()  # doctest: +SKIP
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from modd.link import codec
from modd.link.frames import Config, ConfigAck, Ping, ProtocolError
from modd.link.receiver import Receiver

from .linkhooks import LinkDown
from .session import LinkSession

log = logging.getLogger("modd.subbroker.link")


class StreamSession(LinkSession):
    """A :class:`LinkSession` fed the bytes of a stream (see the module)."""

    def _setup(self) -> None:
        # one try each, as long as a connection may take: a peer that answers nothing
        # is not a lost datagram
        self.handshake_wait_s = self.ping_wait_s = self._opt.connect_timeout_s
        self.receiver = Receiver()
        self._splitter = codec.FrameSplitter()
        #: bytes the transport holds that are not fed yet (the socket's receive queue)
        self.backlog: Callable[[], int] = lambda: 0
        self._pinged = False

    def begin(self) -> None:
        self._splitter = codec.FrameSplitter()
        self._pinged = False
        super().begin()

    def feed(self, data: bytes) -> None:
        """Bytes read from the stream; every whole frame is handled."""
        self.stats.bytes_in += len(data)
        self._splitter.buf += data
        while (frame := self._splitter.pop()) is not None:
            self.heard()
            self._pinged = False
            if self.handshaking:
                self.stats.frames_in += 1
                self.on_handshake(codec.decode(frame), strict=True)
            elif codec.is_data_type(frame.type):
                self.stats.frames_in += 1
                self._on_data(frame)
            else:
                self.on_frame(frame)

    def _wrap(self, frame: bytes) -> list[bytes]:
        return [frame]

    def _accept_config(self, config: Config, ack: ConfigAck) -> None:
        self.receiver.add_config(config, ack.epoch_ns)

    def _check_silence(self, now: float) -> None:
        timeout = self.liveness_s()
        silent = now - self._last_in
        if silent > timeout:
            raise LinkDown(f"no frame for {silent:.1f} s")
        if silent > timeout / 2 and not self._pinged:
            self.send(codec.encode(Ping(b"alive")))
            self._pinged = True

    def _on_data(self, frame: codec.RawFrame) -> None:
        try:
            windows = self.receiver.on_frame(frame)
        except ProtocolError as exc:
            # DATA of a config this process never sent (the PubBroker still runs
            # the previous SubBroker's until our CONFIG applies), or out of
            # sequence: skipped until the next sync frame, never fatal.
            self.stats.bad_frames += 1
            if self.stats.bad_frames % 100 == 1:
                log.info("DATA skipped (%d so far): %s", self.stats.bad_frames, exc)
            return
        self.stats.data_frames += 1
        self.stats.last_data_ns = self.clock.time_ns()
        if windows:
            self.handler.on_windows(windows)
            waiting = len(self._splitter.buf) + self.backlog()
            self.stats.backpressure.observe(windows[0].end_ns, waiting, self.clock.time_ns())
