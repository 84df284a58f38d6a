"""A ZeroMQ subscriber of the system's PUB streams."""

import os
import stat
import time
from typing import Iterable, Iterator, List, Optional

from ._deps import require
from .messages import Message, decode_message

zmq = require("zmq")

DEFAULT_TOPICS = ("frame/", "event")


def _read_key(path: str, secret: bool) -> bytes:
    """The Z85 key of a tactile_keygen file: NAME.pub holds the 'public:' line; NAME.key holds
    'public:' and 'secret:' lines (docs/security.md). As the C++ programs: a secret key file
    that anyone but its owner may read or write is refused, and no message quotes a key."""
    if secret:
        mode = os.stat(path).st_mode
        if mode & 0o077:
            raise ValueError(
                f"{path}: a secret key file must be readable by its owner only "
                f"(mode {stat.S_IMODE(mode):04o}); run: chmod 600 {path}")
    with open(path, "r", encoding="ascii") as f:
        text = f.read()
    keys = {}
    for line in text.splitlines():
        if not line or line.startswith("#") or ":" not in line:
            continue
        name, value = line.split(":", 1)
        keys[name.strip()] = value.strip()
    key = keys.get("secret" if secret else "public")
    if key is None or len(key) != 40:
        kind = "secret" if secret else "public"
        raise ValueError(f"{path}: no valid '{kind}:' key (40 Z85 characters)")
    return key.encode("ascii")


class Subscriber:
    """Subscribes to publishers and yields their messages as Protobuf objects.

    >>> sub = Subscriber(["tcp://127.0.0.1:5555"], topics=["frame/"])
    >>> for m in sub.messages(timeout_s=5):
    ...     print(m.body.sensor_id, m.body.sequence)

    ``server_key``: a publisher's NAME.pub for CURVE (then every endpoint is CURVE);
    ``client_key``: this subscriber's NAME.key (default: a fresh key pair).
    Messages that do not decode are skipped and counted in ``undecodable``.
    """

    def __init__(
        self,
        endpoints: Iterable[str],
        topics: Iterable[str] = DEFAULT_TOPICS,
        server_key: Optional[str] = None,
        client_key: Optional[str] = None,
        context: Optional[zmq.Context] = None,
    ):
        self.endpoints: List[str] = list(endpoints)
        if not self.endpoints:
            raise ValueError("no endpoint given")
        self._ctx = context or zmq.Context.instance()
        self._socket = self._ctx.socket(zmq.SUB)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.setsockopt(zmq.MAXMSGSIZE, 64 << 20)
        if server_key is not None:
            if client_key is not None:
                public, secret = _read_key(client_key, False), _read_key(client_key, True)
            else:
                public, secret = zmq.curve_keypair()
            self._socket.curve_serverkey = _read_key(server_key, False)
            self._socket.curve_publickey = public
            self._socket.curve_secretkey = secret
        for t in topics:
            self._socket.setsockopt(zmq.SUBSCRIBE, t.encode())
        for e in self.endpoints:
            self._socket.connect(e)
        self.undecodable = 0

    def close(self) -> None:
        self._socket.close(0)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def receive(self, timeout_s: float = 1.0) -> Optional[Message]:
        """The next message that decodes, or None after ``timeout_s``."""
        deadline = time.monotonic() + timeout_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not self._socket.poll(int(left * 1000) + 1, zmq.POLLIN):
                return None
            parts = self._socket.recv_multipart(zmq.NOBLOCK)
            if len(parts) != 2:
                self.undecodable += 1
                continue
            m = decode_message(parts[0].decode("utf-8", "replace"), parts[1])
            if m is None:
                self.undecodable += 1
                continue
            return m

    def messages(self, timeout_s: Optional[float] = None) -> Iterator[Message]:
        """Messages until none came for ``timeout_s`` (None: forever)."""
        while True:
            m = self.receive(timeout_s if timeout_s is not None else 3600.0)
            if m is None:
                if timeout_s is not None:
                    return
                continue
            yield m

    def frames(self, timeout_s: Optional[float] = None):
        """TactileFrames only."""
        for m in self.messages(timeout_s):
            if m.kind == "tactile_frame":
                yield m.body

    def events(self, timeout_s: Optional[float] = None):
        """Events only."""
        for m in self.messages(timeout_s):
            if m.kind == "event":
                yield m.body
