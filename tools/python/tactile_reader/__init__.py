"""Read the tactile slippage control system's messages from Python.

- ``Subscriber``: subscribes to sensor_node, hand_node and rig publishers (ZeroMQ, optionally
  CURVE) and yields Messages (topic, kind, Protobuf object) for TactileFrames, Events,
  SensorStats and GroundTruth.
- ``LogReader`` / ``read_log``: reads a tactile_record log (docs/recording.md) record by record,
  reporting a truncated tail the way the C++ reader does; ``LogRecord.decode()`` is the record's
  Protobuf message.

The Protobuf classes are generated from proto/ at build time into the build tree (``tactile.v1``
package beside this one): put ``BUILD/tools/python`` on ``PYTHONPATH``.

The names below are imported on first use, so that ``python3 -m tactile_reader`` can report a
missing Debian module (python3-protobuf, python3-zstandard, python3-zmq) in one line rather than
a traceback; a program that imports them gets ``MissingDependency`` (an ImportError) with the
same message.
"""

import importlib

from ._deps import MissingDependency

_EXPORTS = {
    "Message": "messages",
    "decode_envelope": "messages",
    "decode_message": "messages",
    "SCHEMA_VERSION": "messages",
    "Subscriber": "subscriber",
    "LogReader": "log",
    "LogRecord": "log",
    "read_log": "log",
    "LOG_FORMAT": "log",
}

__all__ = ["MissingDependency", *_EXPORTS]


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'tactile_reader' has no attribute '{name}'")
    value = getattr(importlib.import_module("." + module, __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
