"""Read the tactile slippage control system's messages from Python.

- ``Subscriber``: subscribes to sensor_node, hand_node and rig publishers (ZeroMQ, optionally
  CURVE) and yields TactileFrames, Events, SensorStats and GroundTruth as Protobuf objects.
- ``LogReader`` / ``read_log``: reads a tactile_record log (docs/recording.md) record by record,
  reporting a truncated tail the way the C++ reader does.

The Protobuf classes are generated from proto/ at build time into the build tree (``tactile.v1``
package beside this one): put ``BUILD/tools/python`` on ``PYTHONPATH``.
"""

from .messages import Message, decode_envelope, SCHEMA_VERSION
from .subscriber import Subscriber
from .log import LogReader, LogRecord, read_log, LOG_FORMAT

__all__ = [
    "Message",
    "decode_envelope",
    "SCHEMA_VERSION",
    "Subscriber",
    "LogReader",
    "LogRecord",
    "read_log",
    "LOG_FORMAT",
]
