"""tactile_reader.arm's ArmServer over real sockets (tcp://127.0.0.1:*), as the C++ ArmServerOverSockets.*
tests: the deadman trips once, a stranger's heartbeat is refused while the peer is alive,
garbage and bad commands are counted and never reach the arm, CURVE refuses a client not in the
list. Its ArmPeer (pure) runs the table of cases the C++ arm::ArmPeer runs
(tests/data/arm_link/arm_peer_cases.json). Time is the test's: every call gets the instant it is
for.

Run by ctest with PYTHONPATH=BUILD/tools/python (hand_node against it: hand_node_test,
HandNode.RunsPhaseOneAgainstThePythonArmSide)."""

import json
import os
import pathlib
import tempfile
import unittest

import zmq

from tactile_reader.arm import ArmBackend, ArmPeer, ArmServer, ArmStateData
from tactile_reader.messages import SCHEMA_VERSION, tactile_pb2

MS = 1_000_000


class RecordingArm(ArmBackend):
    def __init__(self):
        self.written, self.holds, self.accept = [], [], True

    def read(self, now_ns):
        return ArmStateData(time_ns=now_ns, active_segment_id=7)

    def write(self, command, now_ns):
        self.written.append(command.WhichOneof("command"))
        return self.accept

    def hold(self, now_ns):
        self.holds.append(now_ns)


def heartbeat():
    e = tactile_pb2.Envelope(schema_version=SCHEMA_VERSION)
    e.heartbeat.sender = "test"
    return e.SerializeToString()


def hold_command(sequence, open_speed=None):
    e = tactile_pb2.Envelope(schema_version=SCHEMA_VERSION)
    e.arm_command.sequence = sequence
    if open_speed is None:
        e.arm_command.hold.SetInParent()
    else:
        e.arm_command.open.speed_mps = open_speed
        e.arm_command.open.distance_m = 0.004
    return e.SerializeToString()


class ArmServerTest(unittest.TestCase):
    def setUp(self):
        self.ctx = zmq.Context()
        self.arm = RecordingArm()
        self.sockets = []

    def tearDown(self):
        for s in self.sockets:
            s.close()
        self.ctx.term()

    def server(self, **kw):
        s = ArmServer(self.arm, "tcp://127.0.0.1:*", heartbeat_period_s=0, context=self.ctx, **kw)
        self.sockets.append(s)
        return s

    def client(self, server, keys=None, server_public=None):
        d = self.ctx.socket(zmq.DEALER)
        d.setsockopt(zmq.LINGER, 0)
        if keys is not None:
            d.curve_publickey, d.curve_secretkey = keys
            d.curve_serverkey = server_public
        d.connect(server.endpoint)
        self.sockets.append(d)
        return d

    def serve_next(self, server, now_ns, timeout_ms=2000):
        if not server.socket.poll(timeout_ms, zmq.POLLIN):
            return False
        return server.serve_one(now_ns)

    def state(self, dealer, timeout_ms=2000):
        if not dealer.poll(timeout_ms, zmq.POLLIN):
            return None
        e = tactile_pb2.Envelope()
        e.ParseFromString(dealer.recv())
        return e.arm_state

    def test_the_deadman_trips_once_and_the_states_say_so(self):
        server = self.server(deadman_s=0.04)
        hand = self.client(server)
        server.check_deadman(10_000 * MS)  # no peer yet
        hand.send(heartbeat())
        self.assertTrue(self.serve_next(server, 100 * MS))
        server.check_deadman(140 * MS)
        self.assertEqual(self.arm.holds, [])
        server.check_deadman(141 * MS)
        server.check_deadman(200 * MS)
        self.assertEqual(self.arm.holds, [141 * MS])
        self.assertEqual(server.deadman_trips, 1)
        self.assertTrue(server.send_state(300 * MS))
        s = self.state(hand)
        self.assertIn(tactile_pb2.ARM_FAULT_DEADMAN, s.faults)
        self.assertEqual(s.active_segment_id, 7)
        hand.send(hold_command(5))
        self.assertTrue(self.serve_next(server, 310 * MS))
        self.assertFalse(server.peer.held)
        server.send_state(320 * MS)
        s = self.state(hand)
        self.assertNotIn(tactile_pb2.ARM_FAULT_DEADMAN, s.faults)
        self.assertEqual(s.last_command_sequence, 5)

    def test_a_hold_a_command_ended_before_any_state_is_still_reported_once(self):
        server = self.server(deadman_s=0.04)
        hand = self.client(server)
        hand.send(heartbeat())
        self.assertTrue(self.serve_next(server, 100 * MS))
        server.check_deadman(141 * MS)
        self.assertEqual(self.arm.holds, [141 * MS])
        hand.send(hold_command(1))
        self.assertTrue(self.serve_next(server, 150 * MS))
        self.assertFalse(server.peer.held)
        self.assertTrue(server.send_state(160 * MS))
        self.assertIn(tactile_pb2.ARM_FAULT_DEADMAN, self.state(hand).faults)
        self.assertTrue(server.send_state(170 * MS))
        self.assertNotIn(tactile_pb2.ARM_FAULT_DEADMAN, self.state(hand).faults)

    def test_a_strangers_heartbeat_is_refused_while_the_peer_is_alive(self):
        server = self.server()
        hand, stranger = self.client(server), self.client(server)
        hand.send(heartbeat())
        self.assertTrue(self.serve_next(server, 0))
        stranger.send(heartbeat())
        self.assertTrue(self.serve_next(server, 10 * MS))
        self.assertEqual(server.strangers, 1)
        server.send_state(20 * MS)
        self.assertIsNotNone(self.state(hand))
        self.assertIsNone(self.state(stranger, 100))

    def test_garbage_and_bad_commands_are_counted_and_never_reach_the_arm(self):
        server = self.server()
        c = self.client(server)
        frame = tactile_pb2.Envelope(schema_version=SCHEMA_VERSION)
        frame.tactile_frame.sensor_id = "left"
        for m in (b"\x08\xff\xff not an envelope", frame.SerializeToString(),
                  hold_command(1, open_speed=float("nan")), hold_command(2, open_speed=-1.0)):
            c.send(m)
            self.assertTrue(self.serve_next(server, 0))
        self.assertEqual((server.garbage, server.invalid_commands, server.commands), (2, 2, 0))
        self.assertEqual(self.arm.written, [])
        self.assertIsNone(server.peer.peer)
        self.arm.accept = False
        c.send(hold_command(3))
        self.assertTrue(self.serve_next(server, 0))
        self.assertEqual(server.invalid_commands, 3)

    def test_under_curve_a_client_not_in_the_list_is_refused(self):
        arm_keys, hand_keys, other_keys = zmq.curve_keypair(), zmq.curve_keypair(), zmq.curve_keypair()
        with tempfile.TemporaryDirectory() as d:
            key, pub = os.path.join(d, "arm.key"), os.path.join(d, "hand.pub")
            with open(key, "w") as f:
                f.write(f"public: {arm_keys[0].decode()}\nsecret: {arm_keys[1].decode()}\n")
            os.chmod(key, 0o600)
            with open(pub, "w") as f:
                f.write(f"public: {hand_keys[0].decode()}\n")
            server = self.server(server_key=key, client_keys=[pub])
        intruder = self.client(server, other_keys, arm_keys[0])
        intruder.send(hold_command(1))
        self.assertFalse(self.serve_next(server, 0, 1000))
        self.assertGreaterEqual(server.refused_clients, 1)
        hand = self.client(server, hand_keys, arm_keys[0])
        hand.send(hold_command(2))
        self.assertTrue(self.serve_next(server, 0))
        self.assertEqual(self.arm.written, ["hold"])

    def test_a_secret_key_others_can_read_is_refused_without_quoting_it(self):
        keys = zmq.curve_keypair()
        with tempfile.TemporaryDirectory() as d:
            key = os.path.join(d, "arm.key")
            with open(key, "w") as f:
                f.write(f"public: {keys[0].decode()}\nsecret: {keys[1].decode()}\n")
            os.chmod(key, 0o640)
            with self.assertRaises(ValueError) as caught:
                self.server(server_key=key)
        self.assertIn("chmod 600", str(caught.exception))
        self.assertNotIn(keys[1].decode(), str(caught.exception))


ARM_PEER_CASES = (
    pathlib.Path(__file__).resolve().parents[3] / "data" / "arm_link" / "arm_peer_cases.json"
)
HEARD = ("accepted", "connected", "new_client", "resumed")


def ns_of_ms(ms):
    return round(ms * 1e6)


class ArmPeerTableTest(unittest.TestCase):
    """The table shared with the C++ arm::ArmPeer's test (its format: the file's "about")."""

    def heard(self, peer, step):
        sender, now = step["from"].encode(), ns_of_ms(step["t_ms"])
        if step["do"] == "heartbeat":
            accepted, connected, new_client = peer.heartbeat(sender, now)
            return dict(accepted=accepted, connected=connected, new_client=new_client,
                        resumed=False)
        connected, new_client, resumed = peer.command(sender, now)
        return dict(accepted=True, connected=connected, new_client=new_client,
                    resumed=resumed)

    def run_step(self, peer, step):
        what = step["do"]
        if what in ("heartbeat", "command"):
            want = step["heard"]
            self.assertLessEqual(set(want), set(HEARD))
            self.assertEqual(self.heard(peer, step), {k: want.get(k, False) for k in HEARD})
        elif what == "deadman_trips":
            self.assertEqual(peer.deadman_trips(ns_of_ms(step["t_ms"])), step["trips"])
        elif what == "report_deadman":
            self.assertEqual(peer.report_deadman(), step["reports"])
        else:
            self.fail(f"unknown step {what}")
        state = {
            "has_peer": lambda: peer.peer is not None,
            "peer": lambda: peer.peer.decode() if peer.peer is not None else None,
            "held": lambda: peer.held,
            "last_heard_ms": lambda: peer.last_heard_ns,
        }
        for key, want in step.get("then", {}).items():
            self.assertIn(key, state)
            self.assertEqual(state[key](), ns_of_ms(want) if key == "last_heard_ms" else want, key)
        return what

    def test_every_case_of_the_table_shared_with_the_cpp_arm_side(self):
        with open(ARM_PEER_CASES) as f:
            table = json.load(f)
        self.assertEqual(table["format"], "tactile-arm-peer-cases/1")
        self.assertGreaterEqual(len(table["cases"]), 9)
        done = set()
        for case in table["cases"]:
            peer = ArmPeer(ns_of_ms(case["deadman_ms"]))
            for i, step in enumerate(case["steps"]):
                with self.subTest(case=case["name"], step=i):
                    done.add(self.run_step(peer, step))
        self.assertEqual(done, {"command", "deadman_trips", "heartbeat", "report_deadman"})


if __name__ == "__main__":
    unittest.main()
