"""The arm controller's side of the arm link in Python, for labs whose arm is scripted in Python
(docs/arm.md, "Python"). The same behaviour on the wire as the C++ ``tactile::arm::ArmServer``:
a ROUTER (CURVE when given keys) that checks every ArmCommand, keeps the peer and its deadman,
answers with ArmStates and Heartbeats, refuses strangers and garbage (counted), and hands the
commands to an ``ArmBackend``: the part a lab writes.

    class MyArm(ArmBackend):
        def read(self, now_ns): ...          # an ArmStateData of the arm now
        def write(self, command, now_ns): ... # follow a checked tactile_pb2.ArmCommand; False: refused
        def hold(self, now_ns): ...          # stop wrist and fingers now, keep the grip

    ArmServer(MyArm(), endpoint="tcp://*:5556").run(state_rate_hz=100)

``python3 -m tactile_reader.arm`` runs it with the built-in ``KinematicArm`` (no physics: it
follows every command exactly), as ``arm_bridge`` does. Time is an argument everywhere (ns of
CLOCK_REALTIME, ``time.time_ns()``).
"""

import abc
import argparse
import math
import signal
import sys
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, List, Optional, Sequence, Tuple

from ._deps import MissingDependency, require

zmq = require("zmq")

from .messages import SCHEMA_VERSION, decode_envelope, tactile_pb2  # noqa: E402
from .subscriber import _read_key  # noqa: E402

Vec3 = Tuple[float, float, float]
FINGERTIPS = 2

# Each fingertip frame's axes (x_f, y_f, z_f) in the wrist frame (docs/protocol.md, "Frames of
# reference"): fingertip 0 sits at -x and squeezes toward +x, fingertip 1 the other way.
FINGERTIP_AXES = (
    ((0.0, -1.0, 0.0), (0.0, 0.0, -1.0), (1.0, 0.0, 0.0)),
    ((0.0, 1.0, 0.0), (0.0, 0.0, -1.0), (-1.0, 0.0, 0.0)),
)


@dataclass
class ArmStateData:
    """What a backend reports (ArmState's fields, docs/protocol.md). The server fills
    ``last_command_sequence`` and ``deadman``, and ``time_ns`` when it is 0."""

    time_ns: int = 0
    wrist_position_m: Vec3 = (0.0, 0.0, 0.0)
    wrist_yaw_rad: float = 0.0
    fingertip_position_m: List[Vec3] = field(default_factory=lambda: [(0.0, 0.0, 0.0)] * 2)
    fingertip_velocity_mps: List[Vec3] = field(default_factory=lambda: [(0.0, 0.0, 0.0)] * 2)
    active_segment_id: int = 0
    segment_done: bool = False
    holding: bool = False
    limit: bool = False
    invalid_command: bool = False


class ArmBackend(abc.ABC):
    """The arm behind the server. Called from the server's thread only. Abstract: a backend
    that leaves out one of the three cannot be made."""

    @abc.abstractmethod
    def read(self, now_ns: int) -> ArmStateData:
        """The arm's state at ``now_ns``."""

    @abc.abstractmethod
    def write(self, command, now_ns: int) -> bool:
        """Follow a checked ``tactile_pb2.ArmCommand`` from ``now_ns`` on; False refuses it."""

    @abc.abstractmethod
    def hold(self, now_ns: int) -> None:
        """Stop the wrist and the fingers now, keeping the grip."""


class ArmPeer:
    """Who the arm answers and the deadman (the C++ ``arm::ArmPeer``): the first client that spoke
    or the last that sent a valid command; another client's heartbeat takes over only during a
    deadman hold, which lasts until a command."""

    def __init__(self, deadman_ns: int):
        self.deadman_ns = deadman_ns
        self.peer: Optional[bytes] = None
        self.held = False
        self.unreported = False  # a hold no ArmState has reported yet
        self.last_heard_ns = 0

    def heartbeat(self, sender: bytes, now_ns: int) -> Tuple[bool, bool, bool]:
        """(accepted, connected, new_client)."""
        connected = self.peer is None
        new_client = not connected and sender != self.peer
        if new_client and not self.held:
            return False, False, True
        self.peer, self.last_heard_ns = sender, now_ns
        return True, connected, new_client

    def command(self, sender: bytes, now_ns: int) -> Tuple[bool, bool, bool]:
        """(connected, new_client, resumed)."""
        connected = self.peer is None
        new_client = not connected and sender != self.peer
        resumed = self.held
        self.held = False
        self.peer, self.last_heard_ns = sender, now_ns
        return connected, new_client, resumed

    def deadman_trips(self, now_ns: int) -> bool:
        if self.peer is None or self.held or now_ns - self.last_heard_ns <= self.deadman_ns:
            return False
        self.held = True
        self.unreported = True
        return True

    def report_deadman(self) -> bool:
        """What the next ArmState says (ARM_FAULT_DEADMAN): held, or held since the last
        ArmState. A command may end the hold before any ArmState reported it; the client must
        still learn that its motion was stopped, so the report is latched until one carried it."""
        report = self.held or self.unreported
        self.unreported = False
        return report


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def _vec(v) -> Vec3:
    return (v.x, v.y, v.z)


def check_command(cmd, fingertip_ids: Sequence[str]) -> bool:
    """The rules of the C++ ``wire::read_arm_command``: every number finite, speeds and distances
    not negative, finger velocities naming the configured fingertips, a command set."""
    kind = cmd.WhichOneof("command")
    if kind == "move_to":
        m = cmd.move_to
        p = m.target.position_m
        return (
            _finite(p.x, p.y, p.z, m.target.yaw_rad, m.max_speed_mps, m.max_yaw_rate_rps)
            and m.max_speed_mps >= 0
            and m.max_yaw_rate_rps >= 0
        )
    if kind == "finger_velocities":
        named = [f.sensor_id for f in cmd.finger_velocities.fingers]
        if len(set(named)) != len(named):
            return False
        for f in cmd.finger_velocities.fingers:
            if f.sensor_id not in fingertip_ids or not _finite(*_vec(f.velocity_mps)):
                return False
        return True
    if kind == "open":
        o = cmd.open
        return _finite(o.speed_mps, o.distance_m) and o.speed_mps >= 0 and o.distance_m >= 0
    return kind in ("hold", "stop")


class KinematicArm(ArmBackend):
    """An arm without physics (the C++ ``arm::KinematicArm``): MoveTo in a straight line at
    max_speed_mps and turning at max_yaw_rate_rps, no acceleration; finger velocities in the
    fingertip frames within the stroke; Open by exactly its distance; Hold stops; after Stop only a
    new MoveTo moves it."""

    def __init__(
        self,
        now_ns: int,
        start: Tuple[float, float, float, float] = (0.35, -0.10, 0.25, 0.0),
        finger_open_m: float = 0.03,
        finger_stroke_m: Tuple[float, float] = (0.0, 0.06),
        fingertip_ids: Sequence[str] = ("left", "right"),
    ):
        self.now_ns = now_ns
        self.ids = list(fingertip_ids)
        self.stroke = finger_stroke_m
        self.state = ArmStateData(
            time_ns=now_ns,
            wrist_position_m=tuple(start[:3]),
            wrist_yaw_rad=start[3],
            fingertip_position_m=[(-finger_open_m, 0.0, 0.0), (finger_open_m, 0.0, 0.0)],
        )
        self.target = None  # (position, yaw, speed, yaw rate) of the MoveTo under way
        self.stopped = False
        self.velocity_f: List[Vec3] = [(0.0, 0.0, 0.0)] * 2
        self.open_left_m: Optional[List[float]] = None

    def advance_to(self, now_ns: int) -> None:
        if now_ns <= self.now_ns:
            return
        dt = (now_ns - self.now_ns) * 1e-9
        self.now_ns = self.state.time_ns = now_ns
        s = self.state
        if self.target is not None:
            pos, yaw, speed, yaw_rate = self.target
            r = [t - p for t, p in zip(pos, s.wrist_position_m)]
            dist = math.sqrt(sum(c * c for c in r))
            step = speed * dt
            there = dist <= step
            s.wrist_position_m = (
                tuple(pos)
                if there
                else tuple(p + step / dist * c for p, c in zip(s.wrist_position_m, r))
            )
            left = yaw - s.wrist_yaw_rad
            turned = abs(left) <= yaw_rate * dt
            s.wrist_yaw_rad = yaw if turned else s.wrist_yaw_rad + math.copysign(yaw_rate * dt, left)
            if there and turned:
                self.target = None
                s.segment_done = True
        s.limit = False
        positions = list(s.fingertip_position_m)
        velocities = list(s.fingertip_velocity_mps)
        for i in range(FINGERTIPS):
            ax = FINGERTIP_AXES[i]
            v_f = self.velocity_f[i]
            if self.open_left_m is not None:
                travel = min(self.open_left_m[i], -v_f[2] * dt)
                self.open_left_m[i] -= travel
                p = tuple(c - travel * z for c, z in zip(positions[i], ax[2]))
                if self.open_left_m[i] <= 0:
                    self.velocity_f[i] = v_f = (0.0, 0.0, 0.0)
            else:
                v_w = [sum(v_f[k] * ax[k][j] for k in range(3)) for j in range(3)]
                p = tuple(c + dt * v for c, v in zip(positions[i], v_w))
            side = -1.0 if i == 0 else 1.0
            along = side * p[0]
            lo, hi = self.stroke
            if along < lo or along > hi:
                p = (side * min(max(along, lo), hi), p[1], p[2])
                self.velocity_f[i] = (self.velocity_f[i][0], self.velocity_f[i][1], 0.0)
                v_f = (v_f[0], v_f[1], 0.0)
                s.limit = True
            positions[i], velocities[i] = p, v_f
        s.fingertip_position_m, s.fingertip_velocity_mps = positions, velocities
        if self.open_left_m is not None and all(d <= 0 for d in self.open_left_m):
            self.open_left_m = None

    def _stop_motion(self) -> None:
        self.target = None
        self.open_left_m = None
        self.velocity_f = [(0.0, 0.0, 0.0)] * 2
        self.state.fingertip_velocity_mps = [(0.0, 0.0, 0.0)] * 2
        self.state.holding = True

    def read(self, now_ns: int) -> ArmStateData:
        self.advance_to(now_ns)
        return self.state

    def write(self, command, now_ns: int) -> bool:
        self.advance_to(now_ns)
        kind = command.WhichOneof("command")
        s = self.state
        if kind == "move_to":
            m = command.move_to
            p = m.target.position_m
            self.target = ((p.x, p.y, p.z), m.target.yaw_rad, m.max_speed_mps, m.max_yaw_rate_rps)
            self.stopped = False
            s.holding = False
            s.active_segment_id = m.segment_id
            s.segment_done = False
            if not m.keep_finger_velocities:
                self.open_left_m = None
                self.velocity_f = [(0.0, 0.0, 0.0)] * 2
            return True
        if kind in ("finger_velocities", "open") and self.stopped:
            return False  # after Stop only a new segment moves the arm
        if kind == "finger_velocities":
            self.open_left_m = None
            self.velocity_f = [(0.0, 0.0, 0.0)] * 2  # a fingertip not named stops
            for f in command.finger_velocities.fingers:
                self.velocity_f[self.ids.index(f.sensor_id)] = _vec(f.velocity_mps)
            s.holding = False
            return True
        if kind == "open":
            self.open_left_m = [command.open.distance_m] * 2
            self.velocity_f = [(0.0, 0.0, -command.open.speed_mps)] * 2
            s.holding = False
            return True
        self._stop_motion()  # hold, stop
        self.stopped = self.stopped or kind == "stop"
        return True

    def hold(self, now_ns: int) -> None:
        self.advance_to(now_ns)
        self._stop_motion()


def _log(level: str, text: str) -> None:
    print(f"tactile_reader.arm {level}: {text}", file=sys.stderr, flush=True)


class ArmServer:
    """The ROUTER of the arm link in front of an ArmBackend (the C++ ``arm::ArmServer``).

    ``server_key``: the arm controller's NAME.key for CURVE; ``client_keys``: the NAME.pub files
    of the clients let in (none: any client that knows the server's public key). Counters:
    ``commands``, ``garbage``, ``strangers``, ``invalid_commands``, ``deadman_trips``,
    ``states_sent``, ``heartbeats_sent``, ``refused_clients`` (by CURVE).
    """

    def __init__(
        self,
        backend: ArmBackend,
        endpoint: str = "tcp://*:5556",
        deadman_s: float = 0.4,
        heartbeat_period_s: float = 0.1,
        fingertip_ids: Sequence[str] = ("left", "right"),
        server_key: Optional[str] = None,
        client_keys: Iterable[str] = (),
        context=None,
    ):
        if not (math.isfinite(deadman_s) and 0 < deadman_s <= 3600):
            raise ValueError(f"deadman {deadman_s} s is not a time between 0 and 3600 s")
        if not (math.isfinite(heartbeat_period_s) and 0 <= heartbeat_period_s <= 3600):
            raise ValueError(f"heartbeat period {heartbeat_period_s} s is not between 0 and 3600 s")
        self.backend = backend
        self.ids = list(fingertip_ids)
        self.peer = ArmPeer(int(deadman_s * 1e9))
        self.heartbeat_ns = int(heartbeat_period_s * 1e9)
        self.last_sent_ns = 0
        self.last_command = 0
        self.commands = self.garbage = self.strangers = self.invalid_commands = 0
        self.deadman_trips = self.states_sent = self.heartbeats_sent = 0
        self.refused_clients = 0
        # The key files first: a bad one leaves no socket behind (an open socket would keep the
        # caller's context from terminating).
        keys = None
        if server_key is not None:
            keys = (
                _read_key(server_key, False),
                _read_key(server_key, True),
                [_read_key(k, False) for k in client_keys],
            )
        elif list(client_keys):
            raise ValueError("client keys need the server's key")
        self._ctx = context or zmq.Context.instance()
        self._auth = None
        self.socket = self._ctx.socket(zmq.ROUTER)
        try:
            self.socket.setsockopt(zmq.LINGER, 0)
            self.socket.setsockopt(zmq.MAXMSGSIZE, 1 << 20)
            if keys is not None:
                self._secure(*keys)
            self.socket.bind(endpoint)
        except Exception:
            self.close()
            raise
        self.endpoint = self.socket.getsockopt_string(zmq.LAST_ENDPOINT)

    def _secure(self, public: bytes, secret: bytes, allowed: List[bytes]) -> None:
        from zmq.auth.thread import ThreadAuthenticator

        server = self

        class Allowed:
            def callback(self, domain, client_key):  # pyzmq passes the Z85 key
                if not allowed or client_key in allowed:
                    return True
                server.refused_clients += 1
                return False

        self._auth = ThreadAuthenticator(self._ctx)
        self._auth.start()
        self._auth.configure_curve_callback("*", credentials_provider=Allowed())
        self.socket.curve_server = True
        self.socket.curve_publickey = public
        self.socket.curve_secretkey = secret

    def close(self) -> None:
        self.socket.close(0)
        if self._auth is not None:
            self._auth.stop()
            self._auth = None

    def refused(self) -> int:
        return self.garbage + self.strangers + self.invalid_commands

    def serve_one(self, now_ns: int) -> bool:
        """Takes one queued message and handles it at ``now_ns``; False when none was queued."""
        try:
            parts = self.socket.recv_multipart(zmq.NOBLOCK)
        except zmq.Again:
            return False
        if len(parts) != 2:
            self.garbage += 1
            return True
        sender, payload = parts
        decoded = decode_envelope(payload)
        if decoded is None:
            self.garbage += 1
            return True
        kind, body = decoded
        if kind == "heartbeat":
            accepted, connected, new_client = self.peer.heartbeat(sender, now_ns)
            if not accepted:
                self.strangers += 1
            elif connected:
                _log("info", "hand_node connected")
            elif new_client:
                _log("info", "a new client takes over after the deadman hold")
            return True
        if kind != "arm_command":
            self.garbage += 1
            return True
        if not check_command(body, self.ids):
            self.invalid_commands += 1
            return True
        connected, new_client, resumed = self.peer.command(sender, now_ns)
        if connected:
            _log("info", "hand_node connected")
        if new_client:
            _log("warn", "commands now come from another client")
        if resumed:
            _log("info", "hand_node commands again after the deadman hold")
        self.commands += 1
        self.last_command = body.sequence
        if not self.backend.write(body, now_ns):
            self.invalid_commands += 1
        return True

    def serve(self, now_ns: int) -> int:
        """Every queued message, then the deadman and the heartbeat."""
        n = 0
        while self.serve_one(now_ns):
            n += 1
        self.check_deadman(now_ns)
        self.heartbeat_if_quiet(now_ns)
        return n

    def check_deadman(self, now_ns: int) -> None:
        if not self.peer.deadman_trips(now_ns):
            return
        self.deadman_trips += 1
        self.backend.hold(now_ns)
        silent_ms = (now_ns - self.peer.last_heard_ns) * 1e-6
        _log("warn", f"deadman: nothing from hand_node for {silent_ms:.0f} ms: arm held")

    def _send(self, env, now_ns: int) -> None:
        env.schema_version = SCHEMA_VERSION
        try:
            self.socket.send_multipart([self.peer.peer, env.SerializeToString()], zmq.NOBLOCK)
        except zmq.ZMQError:
            pass  # the peer is gone or its queue is full: its silence trips the deadman
        self.last_sent_ns = now_ns

    def send_state(self, now_ns: int) -> bool:
        """Sends the peer the backend's state (DEADMAN while held, and once after a hold a command
        ended before any state reported it); False without a peer."""
        if self.peer.peer is None:
            return False
        s = self.backend.read(now_ns)
        env = tactile_pb2.Envelope()
        a = env.arm_state
        a.time_ns = s.time_ns or now_ns
        a.wrist.position_m.x, a.wrist.position_m.y, a.wrist.position_m.z = s.wrist_position_m
        a.wrist.yaw_rad = s.wrist_yaw_rad
        for i, sensor_id in enumerate(self.ids):
            f = a.fingertips.add()
            f.sensor_id = sensor_id
            f.position_m.x, f.position_m.y, f.position_m.z = s.fingertip_position_m[i]
            f.velocity_mps.x, f.velocity_mps.y, f.velocity_mps.z = s.fingertip_velocity_mps[i]
        a.active_segment_id = s.active_segment_id
        a.segment_done = s.segment_done
        if self.peer.report_deadman():
            a.faults.append(tactile_pb2.ARM_FAULT_DEADMAN)
        if s.limit:
            a.faults.append(tactile_pb2.ARM_FAULT_LIMIT)
        if s.invalid_command:
            a.faults.append(tactile_pb2.ARM_FAULT_INVALID_COMMAND)
        a.last_command_sequence = self.last_command
        a.holding = s.holding
        self._send(env, now_ns)
        self.states_sent += 1
        self.check_deadman(now_ns)
        return True

    def heartbeat_if_quiet(self, now_ns: int) -> None:
        if self.heartbeat_ns == 0 or self.peer.peer is None:
            return
        if now_ns - self.last_sent_ns < self.heartbeat_ns:
            return
        env = tactile_pb2.Envelope()
        env.heartbeat.time_ns = now_ns
        env.heartbeat.sender = "tactile_reader.arm"
        self._send(env, now_ns)
        self.heartbeats_sent += 1

    def run(
        self,
        state_rate_hz: float = 100.0,
        stop: Callable[[], bool] = lambda: False,
        clock: Callable[[], int] = time.time_ns,
    ) -> None:
        """Serves until ``stop()``: messages as they come, the deadman at least every 5 ms, an
        ArmState at the state rate; on the way out the arm is held."""
        period_ns = int(1e9 / state_rate_hz)
        next_state = clock() + period_ns
        while not stop():
            wait_ms = min(max((next_state - clock()) // 1_000_000, 0), 5)
            self.socket.poll(wait_ms, zmq.POLLIN)
            self.serve(clock())
            now = clock()
            if now >= next_state:
                self.send_state(now)
                next_state = max(next_state + period_ns, now)
        self.backend.hold(clock())


def _floats(n: int):
    def parse(text: str):
        try:
            values = tuple(float(v) for v in text.split(","))
        except ValueError:
            raise argparse.ArgumentTypeError(f"'{text}' is not {n} numbers separated by commas")
        if len(values) != n or not _finite(*values):
            raise argparse.ArgumentTypeError(f"'{text}' is not {n} finite numbers")
        return values

    return parse


def main(argv: Optional[Sequence[str]] = None) -> int:
    p = argparse.ArgumentParser(
        prog="python3 -m tactile_reader.arm",
        description="The arm controller's end of the arm link (docs/arm.md) with a kinematic arm "
        "that follows every command exactly (no physics), as arm_bridge; in Python, subclass "
        "tactile_reader.arm.ArmBackend for a lab's arm.",
    )
    p.add_argument("--endpoint", default="tcp://*:5556", help="ROUTER endpoint to bind")
    p.add_argument("--key", help="CURVE: the arm controller's key pair (NAME.key)")
    p.add_argument("--client", action="append", default=[], help="with --key, a client NAME.pub")
    p.add_argument("--deadman", type=float, default=0.4, help="hold after this long silent (s)")
    p.add_argument("--heartbeat", type=float, default=0.1, help="heartbeat when quiet (s); 0: never")
    p.add_argument("--state-rate", type=float, default=100.0, help="ArmStates a second")
    p.add_argument("--fingertips", default="left,right", help="sensor ids of fingertip 0 and 1")
    p.add_argument("--start", type=_floats(4), default=(0.35, -0.10, 0.25, 0.0),
                   help="kinematic arm: the wrist's start pose x,y,z (m),yaw (rad)")
    p.add_argument("--finger-open", type=float, default=0.03,
                   help="kinematic arm: each fingertip's distance from the grasp centre (m)")
    a = p.parse_args(argv)
    ids = a.fingertips.split(",")
    if len(ids) != 2 or not all(ids):
        p.error("--fingertips takes two sensor ids separated by a comma")
    if not (0 < a.state_rate <= 10000):
        p.error("--state-rate must be between 0 and 10000")
    if a.client and not a.key:
        p.error("--client needs --key")
    stopping = []
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, lambda *_: stopping.append(True))
    try:
        arm = KinematicArm(time.time_ns(), a.start, a.finger_open, fingertip_ids=ids)
        server = ArmServer(arm, a.endpoint, a.deadman, a.heartbeat, ids, a.key, a.client)
    except (OSError, ValueError, zmq.ZMQError) as e:
        print(f"tactile_reader.arm: {e}", file=sys.stderr)
        return 1
    _log("info", f"arm controller on {server.endpoint}, deadman {a.deadman * 1e3:.0f} ms, "
         f"ArmState at {a.state_rate:g} Hz")
    server.run(a.state_rate, stop=lambda: bool(stopping))
    _log("info", f"stopped: arm held; commands {server.commands} (refused {server.refused()}: "
         f"garbage {server.garbage}, strangers {server.strangers}, invalid "
         f"{server.invalid_commands}), deadman trips {server.deadman_trips}, states sent "
         f"{server.states_sent}, clients refused by CURVE {server.refused_clients}")
    server.close()
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except MissingDependency as e:
        print(f"tactile_reader.arm: {e}", file=sys.stderr)
        sys.exit(1)
