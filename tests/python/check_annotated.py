#!/usr/bin/env python3
"""Independent check of `trajdrift eval --annotate`, with the Python `mcap` package (not our Rust code).

usage: check_annotated.py INPUT.mcap ANNOTATED.mcap REPORT.json

Checks that every input message is in the annotated file with identical channel id, topic, sequence,
log/publish times and bytes; that each /trajdrift/<name>/aligned channel has one message per input
message of the estimate topic, with header stamp and log time shifted by round(applied_s * 1e9) ns and
every other byte unchanged; one drift_error message per window; curvature channels; the `trajdrift`
metadata record and the `trajdrift-report.json` attachment equal to the report. Exits 1 on a mismatch.
"""
import json
import struct
import sys
from collections import Counter, defaultdict

from mcap.reader import make_reader


def load(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        messages = []
        channels = {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            channels[channel.id] = (channel.topic, schema.name if schema else "", channel.message_encoding)
            messages.append((channel.id, message.sequence, message.log_time, message.publish_time, bytes(message.data)))
        attachments = [(a.name, bytes(a.data)) for a in reader.iter_attachments()]
        metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
    return channels, messages, attachments, metadata


def stamp(data):
    fmt = "<iI" if data[1] == 1 else ">iI"
    sec, nsec = struct.unpack(fmt, data[4:12])
    return sec * 1_000_000_000 + nsec


def main():
    inp, out, report_path = sys.argv[1:4]
    report = json.load(open(report_path))
    a_ch, a_msgs, a_att, a_meta = load(inp)
    b_ch, b_msgs, b_att, b_meta = load(out)
    errors = []
    for cid, ch in a_ch.items():
        if b_ch.get(cid) != ch:
            errors.append(f"channel {cid} {ch} changed to {b_ch.get(cid)}")
    new = {cid: ch[0] for cid, ch in b_ch.items() if cid not in a_ch}
    if not all(t.startswith("/trajdrift/") for t in new.values()):
        errors.append(f"unexpected new channels {new}")
    copied = [m for m in b_msgs if m[0] not in new]
    if Counter(copied) != Counter(a_msgs):
        errors.append(f"copied messages differ: {len(copied)} vs {len(a_msgs)} input messages")
    for att in a_att:
        if att not in b_att:
            errors.append(f"attachment {att[0]} lost")
    for meta in a_meta:
        if meta not in b_meta:
            errors.append(f"metadata {meta[0]} lost")
    counts = Counter(new[m[0]] for m in b_msgs if m[0] in new)
    by_topic = defaultdict(list)
    for m in a_msgs:
        by_topic[a_ch[m[0]][0]].append(m)
    for est in report["estimates"]:
        name, topic = est["name"], est["topic"]
        dt_ns = round(est["time_offset"]["applied_s"] * 1e9)
        windows = sum(len(d["per_window"]) for d in est["drift_error"])
        if counts[f"/trajdrift/{name}/drift_error"] != windows:
            errors.append(f"{name}: {counts[f'/trajdrift/{name}/drift_error']} drift_error messages, {windows} windows")
        if counts[f"/trajdrift/{name}/curvature"] == 0:
            errors.append(f"{name}: no curvature message")
        aligned_id = next((c for c, t in new.items() if t == f"/trajdrift/{name}/aligned"), None)
        aligned = [m for m in b_msgs if m[0] == aligned_id]
        source = by_topic.get(topic)
        if source is None:
            if len(aligned) != est["samples"]:
                errors.append(f"{name}: {len(aligned)} aligned poses, {est['samples']} samples")
            continue
        if len(aligned) != len(source):
            errors.append(f"{name}: {len(aligned)} aligned messages, {len(source)} on {topic}")
        for i, o in zip(source, aligned):
            if o[2] != i[2] + dt_ns or stamp(o[4]) != stamp(i[4]) + dt_ns or o[4][12:] != i[4][12:] or o[4][:4] != i[4][:4]:
                errors.append(f"{name}: aligned message at log time {i[2]} not shifted by exactly {dt_ns} ns")
                break
    if counts["/trajdrift/reference/curvature"] == 0:
        errors.append("no reference curvature message")
    meta = dict(b_meta).get("trajdrift")
    if meta is None or "tool.version" not in meta:
        errors.append("metadata record `trajdrift` missing or without tool.version")
    att = dict(b_att).get("trajdrift-report.json")
    if att is None or json.loads(att) != report:
        errors.append("attachment trajdrift-report.json missing or different from the report")
    if errors:
        for e in errors:
            print(f"{out}: {e}", file=sys.stderr)
        return 1
    print(f"{out}: ok ({len(a_msgs)} input messages identical; new: {dict(sorted(counts.items()))})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
