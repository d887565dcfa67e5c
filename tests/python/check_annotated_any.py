#!/usr/bin/env python3
"""Independent check of `trajdrift eval --annotate` on inputs that are not one MCAP file: ROS 1 bags,
rosbag2 folders (MCAP or sqlite3 storage) and missions of several bags. Inputs are read with `rosbags`,
the output with the Python `mcap` package and the `mcap-ros1-support` / `mcap-ros2-support` decoders
(not our Rust code).

usage: check_annotated_any.py INPUT [INPUT...] ANNOTATED.mcap REPORT.json

Checks that every input message is in the output on its topic with identical bytes and log time (the
multiset per topic is equal, so counts per topic are equal); that every output message of an input
channel decodes with its channel's schema; that each /trajdrift/<name>/aligned channel holds one
message per message of the estimate topic, decoded header stamp and log time shifted by
round(applied_s * 1e9) ns; and that the trajdrift channels are there. Exits 1 on a mismatch.
"""
import json
import sys
from collections import Counter, defaultdict
from pathlib import Path

from mcap.reader import make_reader
from mcap_ros1.decoder import DecoderFactory as Ros1Decoders
from mcap_ros2.decoder import DecoderFactory as Ros2Decoders
from rosbags.highlevel import AnyReader


def load_inputs(paths):
    """topic -> list of (log time ns, bytes), in reading order."""
    out = defaultdict(list)
    for p in paths:
        with AnyReader([Path(p)]) as reader:
            for conn, t, raw in reader.messages():
                out[conn.topic].append((t, bytes(raw)))
    return out


def stamp_ns(msg):
    s = msg.header.stamp
    sec = getattr(s, "sec", None)
    if sec is None:
        sec = getattr(s, "secs")
    nsec = getattr(s, "nanosec", None)
    if nsec is None:
        nsec = getattr(s, "nsecs")
    return sec * 1_000_000_000 + nsec


def main():
    *inputs, out, report_path = sys.argv[1:]
    report = json.load(open(report_path))
    expected = load_inputs(inputs)
    factories = [Ros1Decoders(), Ros2Decoders()]
    decoders = {}
    got = defaultdict(list)
    decoded_stamps = defaultdict(list)
    undecodable = Counter()
    with open(out, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            topic = channel.topic
            got[topic].append((message.log_time, bytes(message.data)))
            if topic.startswith("/trajdrift/") and not topic.endswith("/aligned"):
                continue
            key = channel.id
            if key not in decoders:
                decoders[key] = next(
                    (d for d in (fac.decoder_for(channel.message_encoding, schema) for fac in factories) if d),
                    None,
                )
            if decoders[key] is None:
                undecodable[topic] += 1
                continue
            msg = decoders[key](message.data)
            if hasattr(msg, "header"):
                decoded_stamps[topic].append((message.log_time, stamp_ns(msg)))
    errors = []
    for topic, msgs in expected.items():
        if Counter(got.get(topic, [])) != Counter(msgs):
            errors.append(f"{topic}: {len(got.get(topic, []))} messages in the output, {len(msgs)} in the input, or bytes/times differ")
    extra = [t for t in got if t not in expected and not t.startswith("/trajdrift/")]
    if extra:
        errors.append(f"unexpected topics {extra}")
    if undecodable:
        errors.append(f"messages the mcap-ros1/ros2 decoders cannot decode: {dict(undecodable)}")
    for est in report["estimates"]:
        name, topic = est["name"], est["topic"]
        dt_ns = round(est["time_offset"]["applied_s"] * 1e9)
        for what in ("drift_error", "curvature"):
            if not got.get(f"/trajdrift/{name}/{what}"):
                errors.append(f"{name}: no {what} message")
        aligned = sorted(decoded_stamps.get(f"/trajdrift/{name}/aligned", []))
        if topic not in expected:
            continue
        source = sorted(decoded_stamps.get(topic, []))
        if len(aligned) != len(source) or not source:
            errors.append(f"{name}: {len(aligned)} aligned messages, {len(source)} on {topic}")
            continue
        shifted = sorted((lt + dt_ns, st + dt_ns) for lt, st in source)
        if shifted != aligned:
            errors.append(f"{name}: aligned stamps are not the input's shifted by exactly {dt_ns} ns")
    if not got.get("/trajdrift/reference/curvature"):
        errors.append("no reference curvature message")
    if errors:
        for e in errors:
            print(f"{out}: {e}", file=sys.stderr)
        return 1
    n = sum(len(v) for v in expected.values())
    new = {t: len(v) for t, v in sorted(got.items()) if t.startswith("/trajdrift/")}
    print(f"{out}: ok ({n} input messages on {len(expected)} topics present with their bytes and times; new: {new})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
