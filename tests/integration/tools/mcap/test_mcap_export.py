"""tactile_mcap checked by an independent reader: a run recorded from the real programs
(fake_run.py) is exported to MCAP, then read by npm's @mcap/core under Node and decoded with
protobufjs from the descriptors embedded in the file (check_mcap.mjs, as Foxglove reads it); the
messages per channel and their fields, named by the json_name protoc gives them (measureTimeUs),
must equal what our own Python reader sees in the log, and the log's header is a Metadata record.
Also the command line: --help, a bad option, an existing output, a damaged log (nothing written).

Run by ctest with PYTHONPATH=BUILD/tools/python:tests/integration/tools/python and TACTILE_MCAP,
TACTILE_RECORD, TACTILE_FAKE_SENSOR. Exits 77 (ctest: skipped) only when node is not installed;
node_modules come from `npm ci` here (scripts/install-deps --test)."""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
NODE = shutil.which("node")
if __name__ == "__main__" and NODE is None:
    print("node is not installed (scripts/install-deps --test installs nodejs): skipped")
    sys.exit(77)  # SKIP_RETURN_CODE: ctest reports it skipped, never passed
MCAP = os.environ["TACTILE_MCAP"]

import fake_run  # noqa: E402
from tactile_reader import LogReader  # noqa: E402


def check(path):
    p = subprocess.run([NODE, os.path.join(HERE, "check_mcap.mjs"), path], capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


class McapExportTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="tactile-mcap-")
        cls.log = os.path.join(cls.dir, "run.tlog")
        fake_run.record(cls.dir, cls.log)
        with LogReader(cls.log) as r:
            cls.records = list(r)
            cls.header = r.header

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def export(self, name, *options):
        out = os.path.join(self.dir, name)
        p = subprocess.run([MCAP, self.log, out, *options], capture_output=True, text=True, timeout=60)
        self.assertEqual(p.returncode, 0, p.stderr)
        return out

    def test_node_reads_what_our_reader_sees(self):
        ours = {}
        for rec in self.records:
            ours.setdefault(rec.topic, []).append(rec)
        for name, options, compression in (("zstd.mcap", [], "zstd"),
                                           ("plain.mcap", ["--compression", "none", "--chunk-kib", "16"], "")):
            with self.subTest(compression=compression or "none"):
                seen = check(self.export(name, *options))
                counts = {t: len(r) for t, r in ours.items()}
                self.assertEqual(seen["indexed"], counts)
                self.assertEqual(seen["stream"], counts)
                self.assertEqual(seen["statistics"]["perTopic"], counts)
                self.assertEqual(seen["statistics"]["messageCount"], len(self.records))
                self.assertEqual(seen["chunkCompression"], [compression])
                self.assertEqual(seen["channels"], {
                    "frame/left": {"schema": "tactile.v1.TactileFrame", "encoding": "protobuf"},
                    "raw/left": {"schema": "tactile.v1.RawFrame", "encoding": "protobuf"},
                    "event": {"schema": "tactile.v1.Event", "encoding": "protobuf"}})
                self.assertTrue(seen["header"]["library"].startswith("tactile_mcap"))
                self.assertEqual(seen["statistics"]["metadataCount"], 1)
                self.assertEqual(seen["streamMetadata"], ["tactile_log_header"])
                h = self.header
                expected = {"format": h.format, "created_ns": str(h.created_ns), "writer": h.writer,
                            "host": h.host, "note": h.note, "log_file": "run.tlog"}
                for i, source in enumerate(h.sources):
                    expected[f"source.{i}.endpoint"] = source.endpoint
                    expected[f"source.{i}.topics"] = ",".join(source.topics)
                    expected[f"source.{i}.curve"] = "true" if source.curve else "false"
                self.assertEqual(seen["metadata"], {"tactile_log_header": expected})
                self.assertEqual(h.format, "tactile-log/1")
                self.assertTrue(h.writer.startswith("tactile_record"))
                self.assertGreater(h.created_ns, 0)
                for topic, records in ours.items():
                    got = seen["messages"][topic]
                    for rec, m in zip(records, got):
                        self.assertEqual(int(m["logTime"]), rec.receive_time_ns)
                        body = rec.decode()
                        # Fields by protoc's json_name (lowerCamelCase), nested messages too.
                        if topic == "frame/left":
                            self.assertEqual(int(m["body"]["sequence"]), body.sequence)
                            self.assertEqual(int(m["publishTime"]), body.publish_timestamp_ns)
                            self.assertEqual(int(m["body"]["publishTimestampNs"]), body.publish_timestamp_ns)
                            self.assertEqual(m["body"]["sensorId"], body.sensor_id)
                            self.assertEqual(m["body"]["measureTimeUs"], body.measure_time_us)
                            self.assertEqual(m["body"]["status"], "FRAME_STATUS_COMPLETE")
                            self.assertEqual([e["fzN"] for e in m["body"]["elements"]],
                                             [e.fz_n for e in body.elements])
                            self.assertEqual([e["contact"] for e in m["body"]["elements"]],
                                             [e.contact for e in body.elements])
                        elif topic == "event":
                            self.assertEqual(m["body"]["text"], body.text)
                            self.assertEqual(int(m["body"]["timeNs"]), body.time_ns)
                            self.assertEqual(int(m["publishTime"]), body.time_ns)
                        else:
                            self.assertEqual(m["body"]["kind"], log_kind_name(body.kind))
                            self.assertEqual(int(m["body"]["tactileSequence"]), body.tactile_sequence)
                            self.assertEqual(int(m["body"]["cameraFrameId"]), body.camera_frame_id)
                            self.assertEqual(m["body"]["pixels"], len(body.pixels))
                            self.assertEqual((m["body"]["width"], m["body"]["height"]), (body.width, body.height))

    def test_command_line(self):
        p = subprocess.run([MCAP, "--help"], capture_output=True, text=True, timeout=30)
        self.assertEqual(p.returncode, 0)
        self.assertIn("MCAP", p.stdout)
        p = subprocess.run([MCAP, self.log, os.path.join(self.dir, "x.mcap"), "--no-such-option"],
                           capture_output=True, text=True, timeout=30)
        self.assertEqual(p.returncode, 2)
        self.assertIn("--no-such-option", p.stderr)
        out = self.export("again.mcap")
        p = subprocess.run([MCAP, self.log, out], capture_output=True, text=True, timeout=30)
        self.assertEqual(p.returncode, 1)
        self.assertIn("again.mcap: exists", p.stderr)
        self.export("again.mcap", "--overwrite")
        # A log damaged in the middle: refused, and neither the output nor a temporary file is left.
        with open(self.log, "rb") as f:
            data = bytearray(f.read())
        middle = len(data) // 2
        data[middle:middle + 64] = bytes(64)
        bad = os.path.join(self.dir, "bad.tlog")
        with open(bad, "wb") as f:
            f.write(data)
        before = set(os.listdir(self.dir))
        p = subprocess.run([MCAP, bad, os.path.join(self.dir, "bad.mcap")], capture_output=True, text=True,
                           timeout=30)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("bad.tlog", p.stderr)
        self.assertEqual(set(os.listdir(self.dir)), before)

    def test_lockfile_names_no_registry(self):
        # .npmrc's omit-lockfile-registry-resolved: npm ci takes the packages from whatever
        # registry the machine is set up for; integrity hashes still pin every byte.
        with open(os.path.join(HERE, "package-lock.json")) as f:
            lock = f.read()
        self.assertNotIn('"resolved"', lock)
        self.assertNotIn("://", lock)
        self.assertGreaterEqual(lock.count('"integrity": "sha512-'), 2)


def log_kind_name(kind):
    from tactile_reader.messages import log_pb2
    return log_pb2.RawFrameKind.Name(kind)


if __name__ == "__main__":
    if not os.path.isdir(os.path.join(HERE, "node_modules", "@mcap", "core")):
        print(f"{HERE}/node_modules is missing: run scripts/install-deps --test (npm ci there)")
        sys.exit(1)
    unittest.main(verbosity=2)
