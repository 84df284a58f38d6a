"""Envelope decoding shared by the subscriber and the log reader."""

from dataclasses import dataclass
from typing import Any, Optional

from ._deps import require

require("google.protobuf")  # first, so that its absence is not reported as a build problem

try:
    from tactile.v1 import tactile_pb2, log_pb2  # generated at build time
except ImportError as e:  # pragma: no cover - a set-up error, said clearly
    raise ImportError(
        "tactile_reader needs the generated tactile.v1 modules: build the project and put "
        "BUILD/tools/python on PYTHONPATH (" + str(e) + ")"
    ) from e

SCHEMA_VERSION = 1


@dataclass
class Message:
    """One message: its topic, what it is, the Protobuf object and the bytes it came in."""

    topic: str
    kind: str  # "tactile_frame", "event", "sensor_stats", "ground_truth", ..., or "raw_frame"
    body: Any  # tactile_pb2.TactileFrame, tactile_pb2.Event, ..., log_pb2.RawFrame
    payload: bytes
    receive_time_ns: Optional[int] = None  # set for messages from a log
    source: Optional[str] = None  # the publisher's endpoint, for messages from a log


def decode_envelope(payload: bytes):
    """Parses an Envelope; returns (kind, body) or None when it does not parse, has another
    schema version or no body (the rules of docs/protocol.md)."""
    env = tactile_pb2.Envelope()
    try:
        env.ParseFromString(payload)
    except Exception:  # google.protobuf.message.DecodeError
        return None
    if env.schema_version != SCHEMA_VERSION:
        return None
    kind = env.WhichOneof("body")
    if kind is None:
        return None
    return kind, getattr(env, kind)


def decode_message(topic: str, payload: bytes) -> Optional[Message]:
    """A message by its topic: raw frames (topic raw/...) are RawFrames, the rest Envelopes."""
    if topic.startswith("raw/"):
        raw = log_pb2.RawFrame()
        try:
            raw.ParseFromString(payload)
        except Exception:
            return None
        return Message(topic, "raw_frame", raw, payload)
    decoded = decode_envelope(payload)
    if decoded is None:
        return None
    return Message(topic, decoded[0], decoded[1], payload)
