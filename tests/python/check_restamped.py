#!/usr/bin/env python3
"""Independent check of `trajdrift restamp`, with the Python `mcap` package (not our Rust code).

usage: check_restamped.py INPUT.mcap RESTAMPED.mcap

Checks that the restamped file holds every input message, in the same order, on the same channel ids
and topics with the same sequence; that messages of topics no domain moved keep their bytes and times;
that each moved message has its header stamp, log time and publish time shifted by one and the same
amount, every other byte unchanged, and that the amount is the moved domain's clock at that time
within 1 µs (the clock read from the attached audit); and that the `trajdrift-audit.json` attachment and
the `trajdrift-restamp` metadata record are there. Exits 1 on a mismatch.
"""
import json
import struct
import sys

from mcap.reader import make_reader


def load(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        channels, messages = {}, []
        for _, channel, message in reader.iter_messages(log_time_order=False):
            channels[channel.id] = channel.topic
            messages.append((channel.id, message.sequence, message.log_time, message.publish_time, bytes(message.data)))
        attachments = {a.name: bytes(a.data) for a in reader.iter_attachments()}
        metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    return channels, messages, attachments, metadata


def stamp_ns(data):
    # ROS 2 CDR: a 4-byte encapsulation header, then builtin_interfaces/Time (int32 sec, uint32 nanosec).
    sec, nsec = struct.unpack_from("<iI", data, 4)
    return sec * 1_000_000_000 + nsec


def clock_at(c, t):
    """The offsets the clock may give at `t` (s): one; near a step of a piecewise clock, either side's
    (a stamp in the stretch a step skips or repeats goes by the segment it lands nearest to)."""
    if c["model"] == "constant":
        return [c["offset_s"]]
    if c["model"] == "linear":
        return [c["offset_s"] - c["drift_ppm"] * 1e-6 * (t - c["t_mid"])]
    segs = c["segments"]
    return [s["offset_s"] for i, s in enumerate(segs)
            if (i == 0 or t >= s["t_start"] - 1.0) and (i + 1 == len(segs) or t < s["t_end"] + 1.0)]


def main():
    src, out = sys.argv[1], sys.argv[2]
    c_in, m_in, _, _ = load(src)
    c_out, m_out, att, meta = load(out)
    errors = []
    if "trajdrift-audit.json" not in att:
        errors.append("the trajdrift-audit.json attachment is missing")
        print("\n".join(errors))
        return 1
    if "trajdrift-restamp" not in meta:
        errors.append("the trajdrift-restamp metadata record is missing")
    audit = json.loads(att["trajdrift-audit.json"])
    topic_of = {s["name"]: s["topic"] for s in audit["sources"]}
    moved = {topic_of[n]: d["clock"] for d in audit["domains"] if not d["reference"] for n in d["sources"]}
    if len(m_in) != len(m_out):
        errors.append(f"{len(m_in)} messages in, {len(m_out)} out")
    shifted = 0
    for a, b in zip(m_in, m_out):
        topic = c_in[a[0]]
        if c_out[b[0]] != topic or a[0] != b[0] or a[1] != b[1]:
            errors.append(f"{topic}: channel or sequence changed")
        elif topic not in moved:
            if a != b:
                errors.append(f"{topic}: message changed")
        else:
            shift = stamp_ns(b[4]) - stamp_ns(a[4])
            want = [w * 1e9 for w in clock_at(moved[topic], (stamp_ns(a[4]) + shift) * 1e-9)]
            off_model = all(abs(shift - w) > 1000 for w in want)
            if b[2] - a[2] != shift or b[3] - a[3] != shift or off_model or a[4][12:] != b[4][12:]:
                errors.append(f"{topic}: seq {a[1]} shifted {shift} ns (log {b[2] - a[2]}, publish {b[3] - a[3]}, model {want})")
            shifted += 1
        if len(errors) > 10:
            break
    if not moved or shifted == 0:
        errors.append("no message moved")
    if errors:
        print("\n".join(errors))
        return 1
    print(f"restamped copy: {len(m_out)} messages, {shifted} moved over {len(moved)} topics, the rest identical")
    return 0


if __name__ == "__main__":
    sys.exit(main())
