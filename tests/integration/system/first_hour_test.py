"""A new user's first hour, after the README: the run recorded from the host for 10 s by
RunSystem.EndpointsReachableFromTheHostAndTheRunRecordedWithRawFrames (the ctest fixture
first_hour) is read back in Python, exported to MCAP and plotted, each with the command the
README gives. One step per ctest test:

    first_hour_test.py read LOG      python3 -m tactile_reader LOG
    first_hour_test.py mcap LOG      tactile_mcap LOG OUT.mcap, read back by @mcap/core under Node
    first_hour_test.py plot LOG      tactile_plot LOG -o DIR
    first_hour_test.py install SCRIPT  scripts/install-deps --list (the demo's install, without
                                     --test) holds python3 and every Debian package the Python
                                     reader imports (tactile_reader._deps.DEBIAN_PACKAGES)

Environment: PYTHONPATH (BUILD/tools/python), TACTILE_MCAP, TACTILE_PLOT, TACTILE_MCAP_CHECK
(tests/integration/tools/mcap/check_mcap.mjs). The mcap step exits 77 (ctest: skipped) only when
node is not installed."""

import collections
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile


def fail(message):
    print(f"first_hour_test: {message}", file=sys.stderr)
    sys.exit(1)


def run(argv, timeout=120):
    p = subprocess.run(argv, capture_output=True, text=True, timeout=timeout)
    if p.returncode != 0:
        fail(f"{' '.join(argv)} exited {p.returncode}: {p.stderr[-2000:]}")
    return p.stdout


def topics_in(log):
    """Counts per topic, by the documented command line of the Python reader."""
    out = run([sys.executable, "-m", "tactile_reader", log])
    counts = collections.Counter()
    for line in out.splitlines():
        fields = line.split()
        if len(fields) < 3:
            fail(f"a line of tactile_reader's output has fewer than 3 fields: {line!r}")
        counts[fields[1]] += 1
    return counts, out


def step_read(log):
    counts, out = topics_in(log)
    # 10 s of both fingertips at 30 fps or more, the grasp's events and the rig's truth.
    for topic in ("frame/left", "frame/right", "truth"):
        if counts[topic] < 100:
            fail(f"{topic}: {counts[topic]} records in 10 s of recording")
    if counts["event"] < 3:
        fail(f"event: {counts['event']} records; the grasp alone has more")
    if " undecodable" in out:
        fail("tactile_reader could not decode some records")
    # decode() gives the protobuf message itself (docs/tools.md); a measured frame carries every
    # one of the 41 elements (a frame that is not COMPLETE carries none).
    from tactile_reader import LogReader
    measured = 0
    with LogReader(log) as reader:
        for rec in reader:
            if rec.topic.startswith("frame/"):
                frame = rec.decode()
                if len(frame.elements) not in (0, 41):
                    fail(f"a TactileFrame with {len(frame.elements)} elements")
                measured += len(frame.elements) == 41
    if measured < 100:
        fail(f"{measured} TactileFrames with their 41 elements in 10 s")
    print(f"read: {sum(counts.values())} records, {measured} measured frames, {dict(counts)}")


def step_mcap(log):
    node = shutil.which("node")
    if node is None:
        print("node is not installed (scripts/install-deps --test installs nodejs): skipped")
        sys.exit(77)
    counts, _ = topics_in(log)
    with tempfile.TemporaryDirectory(prefix="first-hour-") as d:
        out = os.path.join(d, "run.mcap")
        run([os.environ["TACTILE_MCAP"], log, out])
        seen = json.loads(run([node, os.environ["TACTILE_MCAP_CHECK"], out]))
    for topic, n in counts.items():
        if seen["indexed"].get(topic) != n or seen["stream"].get(topic) != n:
            fail(f"{topic}: {n} records in the log, {seen['indexed'].get(topic)} read by index and "
                 f"{seen['stream'].get(topic)} front to back from the MCAP file")
    if set(seen["indexed"]) != set(counts):
        fail(f"channels {sorted(seen['indexed'])} in the MCAP file, topics {sorted(counts)} in the log")
    print(f"mcap: {sum(counts.values())} messages on {len(counts)} channels read back by @mcap/core")


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n":
        fail(f"{path} is not a PNG file")
    return struct.unpack(">II", head[16:24])


def step_plot(log):
    with tempfile.TemporaryDirectory(prefix="first-hour-") as d:
        run([os.environ["TACTILE_PLOT"], log, "-o", d])
        drawn = sorted(f for f in os.listdir(d) if f.endswith(".png"))
        for name in ("timeline.png", "fig10.png"):
            if not any(f.startswith(name[:-4]) for f in drawn):
                fail(f"no {name} among {drawn}")
        for name in drawn:
            w, h = png_size(os.path.join(d, name))
            if w < 400 or h < 300:
                fail(f"{name} is {w} x {h} pixels")
    print(f"plot: {', '.join(drawn)}")


def step_install(script):
    from tactile_reader._deps import DEBIAN_PACKAGES

    listed = set(run(["bash", script, "--list"]).split())
    missing = sorted(({"python3"} | set(DEBIAN_PACKAGES.values())) - listed)
    if missing:
        fail(f"{script} (the demo's install) leaves out {', '.join(missing)}, which "
             "'python3 -m tactile_reader' needs")
    print(f"install: {', '.join(sorted(DEBIAN_PACKAGES.values()))} in the demo's install")


def main(argv):
    if len(argv) == 3 and argv[1] == "install":
        step_install(argv[2])
        return 0
    steps = {"read": step_read, "mcap": step_mcap, "plot": step_plot}
    if len(argv) != 3 or argv[1] not in steps:
        print(f"usage: {argv[0]} read|mcap|plot LOG | install SCRIPT", file=sys.stderr)
        return 2
    if not os.path.isfile(argv[2]):
        fail(f"{argv[2]}: no recording (the first_hour fixture, RunSystem.*, makes it)")
    steps[argv[1]](argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
