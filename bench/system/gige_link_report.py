#!/usr/bin/env python3
"""The report of scripts/bench-gige-link: per run (topology-roi), from its recording of
sensor_node's frames and stats: frames per second received per camera, incomplete frames,
camera timestamp -> frame received (p50, p99, max), the frame's computed wire time at the link
rate and the load the cameras need of each link at the frame rate asked. Writes OUT/gige-link.md and OUT/gige-link.json, prints the
table."""
import argparse
import json
import math
import os
import re
import sys

from tactile_reader.log import read_log
from tactile_reader.messages import decode_envelope

# Bytes of one GVSP data packet besides its image bytes inside the packet size (IPv4 20, UDP 8,
# GVSP 8), and on the wire around it (Ethernet header 14, FCS 4, preamble 8, inter-frame gap 12).
GVSP_HEADERS = 36
ETHERNET_OVERHEAD = 38
# The leader and trailer packets of a frame (GVSP headers and about 40 bytes each).
LEADER_TRAILER_WIRE = 2 * (GVSP_HEADERS + 48 + ETHERNET_OVERHEAD)


def rate_bps(text):
    m = re.fullmatch(r"([0-9]+)(kbit|mbit|gbit)", text)
    if not m:
        raise SystemExit(f"gige_link_report: --rate '{text}': give tc's form, e.g. 1gbit")
    return int(m.group(1)) * {"kbit": 1e3, "mbit": 1e6, "gbit": 1e9}[m.group(2)]


def wire_time_s(image_bytes, packet_size, bps):
    """The time a frame of image_bytes takes on the link: its data packets, leader and trailer."""
    per_packet = packet_size - GVSP_HEADERS
    packets = math.ceil(image_bytes / per_packet)
    wire_bytes = image_bytes + packets * (GVSP_HEADERS + ETHERNET_OVERHEAD) + LEADER_TRAILER_WIRE
    return wire_bytes * 8 / bps


def nearest_rank(values, q):
    if not values:
        return float("nan")
    v = sorted(values)
    return v[max(0, min(len(v) - 1, math.ceil(q * len(v)) - 1))]


def summarise(path, bps, packet_size, asked_fps):
    sensors = {}
    first_ns, last_ns = None, None
    for rec in read_log(path):
        decoded = decode_envelope(rec.payload)
        if decoded is None:
            continue
        kind, body = decoded
        s = sensors.setdefault(body.sensor_id, {"frames": 0, "incomplete": 0, "lat_ms": [],
                                                "region": None})
        if kind == "tactile_frame":
            s["frames"] += 1
            first_ns = rec.receive_time_ns if first_ns is None else first_ns
            last_ns = rec.receive_time_ns
            if body.status != 1:  # FRAME_STATUS_COMPLETE
                s["incomplete"] += 1
                continue
            s["lat_ms"].append((body.receive_timestamp_ns - body.camera_timestamp_ns) / 1e6)
        elif kind == "sensor_stats" and body.HasField("region"):
            r = body.region
            s["region"] = (r.x, r.y, r.width, r.height)
    seconds = (last_ns - first_ns) / 1e9 if first_ns is not None and last_ns > first_ns else 0
    out = {}
    for sid, s in sorted(sensors.items()):
        region = s["region"]
        image_bytes = region[2] * region[3] if region else None  # Mono8
        wire = wire_time_s(image_bytes, packet_size, bps) if image_bytes else None
        fps = s["frames"] / seconds if seconds > 0 else 0
        out[sid] = {
            "frames": s["frames"],
            "incomplete": s["incomplete"],
            "fps": fps,
            "region": region,
            "image_bytes": image_bytes,
            "wire_time_ms": wire * 1e3 if wire else None,
            # What the camera needs of the link at the rate asked (what it got: fps).
            "link_load_needed": wire * asked_fps if wire else None,
            "camera_to_received_ms": {
                "p50": nearest_rank(s["lat_ms"], 0.5),
                "p99": nearest_rank(s["lat_ms"], 0.99),
                "max": max(s["lat_ms"]) if s["lat_ms"] else float("nan"),
            },
        }
    return out


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rate", required=True)
    ap.add_argument("--fps", type=float, required=True)
    ap.add_argument("--packet-size", type=int, required=True)
    ap.add_argument("--mtu", type=int, default=1500, help="the links' MTU (for the table's heading)")
    ap.add_argument("--out", required=True)
    ap.add_argument("runs", nargs="+", help="topology-roi, each with OUT/RUN.tlog")
    a = ap.parse_args(argv)
    bps = rate_bps(a.rate)
    results = {}
    rows = []
    for run in a.runs:
        path = os.path.join(a.out, run + ".tlog")
        if not os.path.exists(path):
            raise SystemExit(f"gige_link_report: {path}: no such file")
        res = summarise(path, bps, a.packet_size, a.fps)
        results[run] = res
        topology = run.split("-")[0]
        link_load = {}
        for sid, r in res.items():
            link = "both" if topology == "shared" else sid
            link_load[link] = link_load.get(link, 0) + (r["link_load_needed"] or 0)
        for sid, r in res.items():
            link = "both" if topology == "shared" else sid
            reg = r["region"]
            lat = r["camera_to_received_ms"]
            rows.append(
                f"| {run} | {sid} | {reg[2]}x{reg[3]} at ({reg[0]}, {reg[1]}) | "
                f"{r['wire_time_ms']:.2f} | {link_load[link] * 100:.0f} % | {r['fps']:.1f} | "
                f"{r['frames']} | {r['incomplete']} | {lat['p50']:.2f} / {lat['p99']:.2f} / "
                f"{lat['max']:.2f} |" if reg else
                f"| {run} | {sid} | (no SensorStats) | | | {r['fps']:.1f} | {r['frames']} | "
                f"{r['incomplete']} | {lat['p50']:.2f} / {lat['p99']:.2f} / {lat['max']:.2f} |")
    header = (
        f"Two cameras asked for {a.fps:g} fps each, links at {a.rate}, MTU {a.mtu}, "
        f"{a.packet_size}-byte GVSP packets.\n\n"
        "| run | camera | region | wire time of a frame, ms | link load needed | "
        "frames/s received | frames | incomplete | camera -> received ms p50 / p99 / max |\n"
        "|---|---|---|---|---|---|---|---|---|\n")
    table = header + "\n".join(rows) + "\n"
    with open(os.path.join(a.out, "gige-link.md"), "w") as f:
        f.write(table)
    with open(os.path.join(a.out, "gige-link.json"), "w") as f:
        json.dump({"rate": a.rate, "fps": a.fps, "mtu": a.mtu, "packet_size": a.packet_size,
                   "runs": results}, f, indent=1)
    print(table)


if __name__ == "__main__":
    main(sys.argv[1:])
