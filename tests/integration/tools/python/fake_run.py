"""A run recorded from the real programs, for the tests of the readers and the exporters:
fake_sensor publishes frames, raw frames and events, tactile_record writes them to a log.
The programs' paths come from TACTILE_RECORD and TACTILE_FAKE_SENSOR."""

import os
import re
import subprocess
import time

FRAMES = 40
# What fake_sensor sends with --raw --events: frames, raw frames and references, events.
EXPECTED = FRAMES + (FRAMES + 1 + FRAMES // 25) + sum(1 for k in range(FRAMES) if k % 10 == 5)


def read_text(path):
    with open(path) as f:
        return f.read()


def wait_for(pattern, read, timeout=20.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = re.search(pattern, read())
        if m:
            return m
        time.sleep(0.005)
    raise AssertionError(f"no match for {pattern!r} in {read()!r}")


def record(directory, log):
    """Records fake_sensor's EXPECTED messages into `log`."""
    out = os.path.join(directory, "fake.out")
    with open(out, "w") as f:
        sensor = subprocess.Popen(
            [os.environ["TACTILE_FAKE_SENSOR"], "--calibration", os.path.join(directory, "left.yaml"),
             "--frames", str(FRAMES), "--raw", "--events", "--wait-subscriptions", "5"],
            stdout=f, stderr=subprocess.DEVNULL)
    try:
        m = wait_for(r"frames=(\S+) events=(\S+)", lambda: read_text(out))
        rec = subprocess.run(
            [os.environ["TACTILE_RECORD"], "-o", log, m.group(1), m.group(2), "--raw-frames", "--count",
             str(EXPECTED)], capture_output=True, text=True, timeout=60)
        assert rec.returncode == 0, rec.stderr
    finally:
        sensor.wait(timeout=20)
