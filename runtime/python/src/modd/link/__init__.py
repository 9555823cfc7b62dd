"""The MoDD link protocol in Python (docs/protocol.md): frames, codec, handshake, slots.

The C++ PubBroker and this codec agree byte for byte on the vectors in contracts/vectors/link/.

Example::

    from modd.link import codec, frames
    wire = codec.encode(frames.Ping(b"\\x01"))
    splitter = codec.FrameSplitter()
    (raw,) = splitter.feed(wire)
    assert codec.decode(raw) == frames.Ping(b"\\x01")
"""

from modd.link.codec import FrameSplitter, RawFrame, decode, decode_data, encode, encode_data
from modd.link.frames import (
    Aggregation,
    Auth,
    AuthOk,
    Challenge,
    Config,
    ConfigAck,
    Data,
    ErrorMsg,
    Hello,
    MsgType,
    Ping,
    Pong,
    Status,
    StreamSpec,
    TopicSpec,
    Value,
    ValueType,
)
from modd.link.schedule import Slot, SlotIterator

__all__ = [
    "Aggregation",
    "Auth",
    "AuthOk",
    "Challenge",
    "Config",
    "ConfigAck",
    "Data",
    "ErrorMsg",
    "FrameSplitter",
    "Hello",
    "MsgType",
    "Ping",
    "Pong",
    "RawFrame",
    "Slot",
    "SlotIterator",
    "Status",
    "StreamSpec",
    "TopicSpec",
    "Value",
    "ValueType",
    "decode",
    "decode_data",
    "encode",
    "encode_data",
]
