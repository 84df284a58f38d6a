"""Reader of tactile_record logs (docs/recording.md): whole zstd frames of length-delimited
tactile.v1.LogRecord messages."""

from dataclasses import dataclass
from typing import Iterator, Optional

from ._deps import require
from .messages import Message, decode_message, log_pb2

zstandard = require("zstandard")

LOG_FORMAT = "tactile-log/1"
_CHUNK = 1 << 20


@dataclass
class LogRecord:
    receive_time_ns: int
    topic: str
    source: str
    kind: int  # log_pb2.PAYLOAD_KIND_ENVELOPE or PAYLOAD_KIND_RAW_FRAME
    payload: bytes

    def decode(self):
        """The record's message as a Protobuf object: the TactileFrame, Event, SensorStats,
        GroundTruth... its Envelope carries, or a RawFrame for a raw/ topic; None when it does not
        decode. ``message()`` gives the same object with its kind."""
        m = self.message()
        return None if m is None else m.body

    def message(self) -> Optional[Message]:
        """The record as a Message (topic, kind, body = what decode() returns, payload, receive
        time, source); None when it does not decode."""
        m = decode_message(self.topic, self.payload)
        if m is not None:
            m.receive_time_ns = self.receive_time_ns
            m.source = self.source
        return m


def _varint(buf: bytes, pos: int):
    value = 0
    shift = 0
    while shift < 64:
        if pos >= len(buf):
            return None, pos
        b = buf[pos]
        pos += 1
        value |= (b & 0x7F) << shift
        if not b & 0x80:
            return value, pos
        shift += 7
    return None, pos


class LogReader:
    """Iterates over a log's records (the header is ``self.header``).

    After the iteration ``status`` is "end", "truncated" (the file ends inside a zstd frame: a
    recorder that was killed; everything before was read) or "corrupt" (a frame that does not
    decode), and ``problem`` says where.
    """

    def __init__(self, path: str):
        self.path = str(path)
        self.status = "reading"
        self.problem = ""
        self.records = 0
        self._file = open(self.path, "rb")
        try:
            self._open()
        except BaseException:
            self._file.close()
            raise

    def _open(self):
        head = self._file.read(4)
        if not head:
            raise ValueError(f"{self.path}: empty file (the recorder stopped before writing anything)")
        if head != b"\x28\xb5\x2f\xfd":
            raise ValueError(f"{self.path}: not a tactile log (it does not start with a zstd frame)")
        self._file.seek(0)
        self._frames = self._frame_contents()
        self._pending = []
        first = self._next_record_raw()
        if first is None or not first.HasField("header"):
            raise ValueError(f"{self.path}: no header ({self.problem or 'no records'})")
        self.header = first.header
        if self.header.format != LOG_FORMAT:
            raise ValueError(f"{self.path}: format '{self.header.format}' is not {LOG_FORMAT}")

    def close(self):
        self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _frame_contents(self) -> Iterator[bytes]:
        dctx = zstandard.ZstdDecompressor()
        offset = 0  # file offset where the current frame starts
        data = b""
        while True:
            dobj = dctx.decompressobj()
            out = []
            consumed_any = False
            consumed = 0
            while True:
                if not data:
                    data = self._file.read(_CHUNK)
                    if not data:
                        if consumed_any:
                            size = self._file.tell()
                            self.status = "truncated"
                            self.problem = (
                                f"{self.path}: truncated tail: the last {size - offset} bytes (from "
                                f"byte {offset}) are an incomplete zstd frame; the {self.records} "
                                "records before it are kept"
                            )
                        else:
                            self.status = "end"
                        return
                consumed_any = True
                try:
                    out.append(dobj.decompress(data))
                except zstandard.ZstdError as e:
                    self.status = "corrupt"
                    self.problem = f"{self.path}: the zstd frame at byte {offset} does not decode: {e}"
                    return
                if dobj.eof:
                    rest = dobj.unused_data
                    consumed += len(data) - len(rest)
                    data = rest
                    break
                consumed += len(data)
                data = b""
            offset += consumed
            yield b"".join(out)

    def _next_record_raw(self):
        while not self._pending:
            frame = next(self._frames, None)
            if frame is None:
                return None
            pos = 0
            records = []
            while pos < len(frame):
                size, pos = _varint(frame, pos)
                if size is None or pos + size > len(frame):
                    self.status = "corrupt"
                    self.problem = f"{self.path}: broken record length inside a frame"
                    return None
                rec = log_pb2.LogRecord()
                rec.ParseFromString(frame[pos : pos + size])
                pos += size
                records.append(rec)
            self._pending = records[::-1]
        return self._pending.pop()

    def __iter__(self) -> Iterator[LogRecord]:
        while True:
            rec = self._next_record_raw()
            if rec is None:
                return
            self.records += 1
            yield LogRecord(rec.receive_time_ns, rec.topic, rec.source, rec.kind, rec.payload)


def read_log(path: str) -> Iterator[LogRecord]:
    """Every record of a log (a truncated tail ends the iteration quietly; use LogReader to see
    its status)."""
    with LogReader(path) as r:
        yield from r
