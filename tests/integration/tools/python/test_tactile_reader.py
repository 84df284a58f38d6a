"""tactile_reader against real programs: a run recorded by tactile_record from fake_sensor is read
from its log file, cut short and read again, and played back by tactile_replay to the Python
subscriber, which must see every TactileFrame and Event byte for byte.

Run by ctest with PYTHONPATH=BUILD/tools/python and the programs' paths in TACTILE_RECORD,
TACTILE_REPLAY and TACTILE_FAKE_SENSOR."""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unittest

import tactile_reader
from tactile_reader import LogReader, Subscriber, read_log

RECORD = os.environ["TACTILE_RECORD"]
REPLAY = os.environ["TACTILE_REPLAY"]
FAKE = os.environ["TACTILE_FAKE_SENSOR"]
FRAMES = 40
# What fake_sensor sends with --raw --events: frames, raw frames and references, events.
EXPECTED = FRAMES + (FRAMES + 1 + FRAMES // 25) + sum(1 for k in range(FRAMES) if k % 10 == 5)


def wait_for(pattern, read, timeout=20.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(pattern, read())
        if m:
            return m
        time.sleep(0.005)
    raise AssertionError(f"no match for {pattern!r} in {read()!r}")


class TactileReaderTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="tactile-py-")
        cls.log = os.path.join(cls.dir, "run.tlog")
        out = os.path.join(cls.dir, "fake.out")
        with open(out, "w") as f:
            sensor = subprocess.Popen(
                [FAKE, "--calibration", os.path.join(cls.dir, "left.yaml"), "--frames", str(FRAMES),
                 "--raw", "--events", "--wait-subscriptions", "5"],
                stdout=f, stderr=subprocess.DEVNULL)
        try:
            m = wait_for(r"frames=(\S+) events=(\S+)", lambda: open(out).read())
            rec = subprocess.run(
                [RECORD, "-o", cls.log, m.group(1), m.group(2), "--raw-frames", "--count",
                 str(EXPECTED)], capture_output=True, text=True, timeout=60)
            assert rec.returncode == 0, rec.stderr
        finally:
            sensor.wait(timeout=20)

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
        self.assertEqual([m.body.sequence for m in frames], list(range(FRAMES)))
        self.assertTrue(all(m.kind == "tactile_frame" for m in frames))
        self.assertEqual(len(frames[0].body.elements), 15)
        raws = [rec.decode() for rec in records if rec.topic == "raw/left"]
        self.assertEqual(raws[0].body.kind, tactile_reader.messages.log_pb2.RAW_FRAME_KIND_REFERENCE)
        self.assertEqual(raws[1].body.tactile_sequence, 0)
        self.assertEqual(len(raws[1].body.pixels), raws[1].body.width * raws[1].body.height)
        events = [rec.decode().body for rec in records if rec.topic == "event"]
        self.assertEqual(len(events), 4)
        self.assertEqual(events[0].text, "event at frame 5")

    def test_a_log_cut_short_keeps_every_whole_frame(self):
        full = list(read_log(self.log))
        data = open(self.log, "rb").read()
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
            endpoint = wait_for(r"publishing on (tcp://\S+)", lambda: open(err_path).read()).group(1)
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


if __name__ == "__main__":
    unittest.main(verbosity=2)
