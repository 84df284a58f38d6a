"""tactile_reader against real programs: a run recorded by tactile_record from fake_sensor is read
from its log file, cut short and read again, and played back by tactile_replay to the Python
subscriber, which must see every TactileFrame and Event byte for byte. The command line: a closed
pipe, usage errors, an interpreter without Debian's modules, a subscriber that hears nothing.

Run by ctest with PYTHONPATH=BUILD/tools/python and the programs' paths in TACTILE_RECORD,
TACTILE_REPLAY and TACTILE_FAKE_SENSOR (fake_run.py records the run)."""

import importlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

import fake_run
import tactile_reader
from tactile_reader import LogReader, Subscriber, read_log
from tactile_reader.messages import log_pb2, tactile_pb2

REPLAY = os.environ["TACTILE_REPLAY"]
FRAMES = fake_run.FRAMES
EXPECTED = fake_run.EXPECTED
read_text = fake_run.read_text
wait_for = fake_run.wait_for


class TactileReaderTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="tactile-py-")
        cls.log = os.path.join(cls.dir, "run.tlog")
        fake_run.record(cls.dir, cls.log)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_log_reader_reads_every_record(self):
        with LogReader(self.log) as r:
            self.assertEqual(r.header.format, "tactile-log/1")
            self.assertTrue(r.header.writer.startswith("tactile_record"))
            records = list(r)
            self.assertEqual(r.status, "end")
        self.assertEqual(len(records), EXPECTED)
        frames = [rec.decode() for rec in records if rec.topic == "frame/left"]
        self.assertEqual([f.sequence for f in frames], list(range(FRAMES)))
        self.assertEqual(len(frames[0].elements), 15)
        raws = [rec.decode() for rec in records if rec.topic == "raw/left"]
        self.assertEqual(raws[0].kind, log_pb2.RAW_FRAME_KIND_REFERENCE)
        self.assertEqual(raws[1].tactile_sequence, 0)
        self.assertEqual(len(raws[1].pixels), raws[1].width * raws[1].height)
        events = [rec.decode() for rec in records if rec.topic == "event"]
        self.assertEqual(len(events), 4)
        self.assertEqual(events[0].text, "event at frame 5")

    def test_decode_returns_the_protobuf_message_and_message_its_kind(self):
        with LogReader(self.log) as r:
            records = list(r)
        kinds = {}
        for rec in records:
            body = rec.decode()
            m = rec.message()
            self.assertIs(type(body), type(m.body))
            self.assertEqual(body, m.body)
            self.assertEqual((m.topic, m.receive_time_ns, m.source), (rec.topic, rec.receive_time_ns, rec.source))
            kinds[m.kind] = type(body)
        self.assertEqual(kinds, {"tactile_frame": tactile_pb2.TactileFrame, "event": tactile_pb2.Event,
                                 "raw_frame": log_pb2.RawFrame})
        garbage = tactile_reader.LogRecord(1, "frame/left", "x", log_pb2.PAYLOAD_KIND_ENVELOPE, b"\xff\xff")
        self.assertIsNone(garbage.decode())
        self.assertIsNone(garbage.message())

    def test_a_log_cut_short_keeps_every_whole_frame(self):
        full = list(read_log(self.log))
        with open(self.log, "rb") as f:
            data = f.read()
        cut = os.path.join(self.dir, "cut.tlog")
        with open(cut, "wb") as f:
            f.write(data[: len(data) - 1000])
        with LogReader(cut) as r:
            got = list(r)
            self.assertEqual(r.status, "truncated")
            self.assertIn("truncated tail", r.problem)
        self.assertGreater(len(got), 0)
        self.assertLess(len(got), len(full))
        for a, b in zip(got, full):
            self.assertEqual(a.payload, b.payload)
        with open(os.path.join(self.dir, "bad.tlog"), "wb") as f:
            f.write(b"not a log")
        with self.assertRaisesRegex(ValueError, "not a tactile log"):
            LogReader(os.path.join(self.dir, "bad.tlog"))

    def test_subscriber_receives_a_replay_byte_for_byte(self):
        recorded = [r for r in read_log(self.log) if r.topic in ("frame/left", "event")]
        err_path = os.path.join(self.dir, "replay.err")
        with open(err_path, "w") as err:
            replay = subprocess.Popen(
                [REPLAY, self.log, "--publish", "tcp://127.0.0.1:*", "--as-fast-as-possible",
                 "--wait-subscriptions", "2"], stdout=subprocess.DEVNULL, stderr=err)
        try:
            endpoint = wait_for(r"publishing on (tcp://\S+)", lambda: read_text(err_path)).group(1)
            got = []
            with Subscriber([endpoint], topics=["frame/", "event"]) as sub:
                for m in sub.messages(timeout_s=10):
                    got.append(m)
                    if len(got) == len(recorded):
                        break
                self.assertEqual(sub.undecodable, 0)
            self.assertEqual(len(got), len(recorded))
            for m, r in zip(got, recorded):
                self.assertEqual(m.topic, r.topic)
                self.assertEqual(m.payload, r.payload)
            frames = [m.body for m in got if m.kind == "tactile_frame"]
            self.assertEqual([f.sequence for f in frames], list(range(FRAMES)))
            self.assertEqual(frames[3].sensor_id, "left")
            events = [m.body for m in got if m.kind == "event"]
            self.assertEqual(len(events), 4)
            self.assertEqual(replay.wait(timeout=20), 0)
        finally:
            if replay.poll() is None:
                replay.kill()
                replay.wait()

    def test_command_line_lists_records(self):
        p = subprocess.run([sys.executable, "-m", "tactile_reader", self.log], capture_output=True,
                           text=True, timeout=60)
        self.assertEqual(p.returncode, 0, p.stderr)
        lines = p.stdout.splitlines()
        self.assertEqual(len(lines), EXPECTED)
        self.assertTrue(any("frame/left tactile_frame seq 39" in l for l in lines))


    def test_a_decision_line_names_the_detector_and_the_slipping_elements(self):
        from tactile_reader.__main__ import _line
        from tactile_reader.messages import Message

        d = tactile_pb2.Decision(phase="LIFT", slip_detector="learned")
        d.fingertips.add(sensor_id="left", slip=True, slipping_elements=2).slipping_element_ids.extend(
            [4, 17])
        d.fingertips.add(sensor_id="right")
        self.assertEqual(_line(Message("decision", "decision", d, b""), 5),
                         "5 decision decision LIFT learned left/SLIP[4,17] right")

    def test_closed_pipe_ends_quietly(self):
        # The reader of the pipe is gone before the first write, as with `| head` on a long log.
        read_end, write_end = os.pipe()
        os.close(read_end)
        try:
            p = subprocess.run([sys.executable, "-m", "tactile_reader", self.log], stdout=write_end,
                               stderr=subprocess.PIPE, text=True, timeout=60)
        finally:
            os.close(write_end)
        self.assertEqual(p.stderr, "")
        self.assertEqual(p.returncode, -signal.SIGPIPE)
        p = subprocess.run(f"'{sys.executable}' -m tactile_reader '{self.log}' | head -n 3", shell=True,
                           capture_output=True, text=True, timeout=60)
        self.assertEqual(p.stderr, "")
        self.assertEqual(len(p.stdout.splitlines()), 3)

    def test_usage_errors_exit_2_and_help_exits_0(self):
        for args in (["--no-such-option", self.log], [], [self.log, "--subscribe", "tcp://127.0.0.1:1"],
                     ["--subscribe", "tcp://127.0.0.1:1", "--silence-timeout", "-1"],
                     ["--subscribe", "tcp://127.0.0.1:1", "--count", "x"]):
            p = run_reader(args)
            self.assertEqual(p.returncode, 2, args)
            self.assertEqual(p.stdout, "", args)
            self.assertIn("usage: python3 -m tactile_reader", p.stderr, args)
        p = run_reader(["--help"])
        self.assertEqual(p.returncode, 0)
        self.assertEqual(p.stderr, "")
        self.assertIn("usage: python3 -m tactile_reader", p.stdout)
        self.assertIn("--silence-timeout", p.stdout)
        p = run_reader([os.path.join(self.dir, "absent.tlog")])
        self.assertEqual(p.returncode, 1)
        self.assertIn("absent.tlog", p.stderr)

    def test_missing_debian_module_is_named_with_the_interpreter(self):
        # -S leaves out site-packages and Debian's dist-packages; PYTHONPATH still applies, so a
        # folder of links lends the interpreter some of Debian's modules and not the others.
        lent = os.path.join(self.dir, "lent")
        os.makedirs(lent, exist_ok=True)
        build = os.environ["PYTHONPATH"]
        cases = [([], [self.log], "google.protobuf", "python3-protobuf"),
                 (["google"], [self.log], "zstandard", "python3-zstandard"),
                 (["google", "zstandard"], ["--subscribe", "tcp://127.0.0.1:1"], "zmq", "python3-zmq")]
        for modules, args, module, package in cases:
            for name in modules:
                link = os.path.join(lent, name)
                if not os.path.lexists(link):
                    os.symlink(list(importlib.import_module(name).__path__)[0], link)
            p = subprocess.run([sys.executable, "-S", "-m", "tactile_reader", *args], capture_output=True,
                               text=True, timeout=60, env=dict(os.environ, PYTHONPATH=f"{build}:{lent}"))
            self.assertEqual(p.returncode, 1, p.stderr)
            self.assertNotIn("Traceback", p.stderr)
            self.assertEqual(len(p.stderr.splitlines()), 1, p.stderr)
            self.assertIn(f"'{module}' from the Debian package {package}", p.stderr)
            self.assertIn(sys.executable, p.stderr)
        # A program importing the library gets the same message as an ImportError.
        p = subprocess.run([sys.executable, "-S", "-c", "from tactile_reader import LogReader"],
                           capture_output=True, text=True, timeout=60, env=dict(os.environ, PYTHONPATH=build))
        self.assertNotEqual(p.returncode, 0)
        self.assertIn("MissingDependency: tactile_reader needs the Python module "
                      "'google.protobuf' from the Debian package python3-protobuf", p.stderr)

    def test_subscriber_that_hears_nothing_names_the_endpoint(self):
        with socket.socket() as s:  # a port nobody publishes on
            s.bind(("127.0.0.1", 0))
            endpoint = f"tcp://127.0.0.1:{s.getsockname()[1]}"
        start = time.monotonic()
        p = run_reader(["--subscribe", endpoint, "--silence-timeout", "0.5"])
        self.assertLess(time.monotonic() - start, 10)
        self.assertEqual(p.returncode, 1)
        self.assertEqual(p.stdout, "")
        self.assertEqual(p.stderr, f"tactile_reader: nothing heard from {endpoint} within 0.5 s\n")

    def test_command_line_subscriber_prints_a_replay(self):
        err_path = os.path.join(self.dir, "replay-cli.err")
        with open(err_path, "w") as err:
            replay = subprocess.Popen(
                [REPLAY, self.log, "--publish", "tcp://127.0.0.1:*", "--as-fast-as-possible",
                 "--wait-subscriptions", "1", "--topic", "frame/"], stdout=subprocess.DEVNULL, stderr=err)
        try:
            endpoint = wait_for(r"publishing on (tcp://\S+)", lambda: read_text(err_path)).group(1)
            p = run_reader(["--subscribe", endpoint, "--count", str(FRAMES)])
            self.assertEqual(p.returncode, 0, p.stderr)
            lines = p.stdout.splitlines()
            self.assertEqual(len(lines), FRAMES)
            self.assertRegex(lines[-1], rf"^\d+ frame/left tactile_frame seq {FRAMES - 1} contact \d+/15$")
            self.assertEqual(replay.wait(timeout=20), 0)
        finally:
            if replay.poll() is None:
                replay.kill()
                replay.wait()


def run_reader(args):
    return subprocess.run([sys.executable, "-m", "tactile_reader", *args], capture_output=True, text=True,
                          timeout=60)


if __name__ == "__main__":
    unittest.main(verbosity=2)
