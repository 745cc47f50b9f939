#!/usr/bin/env python3
"""Decodes every message of a run's `run.mcap` with the ROS 2 reader of the MCAP project
(`mcap-ros2-support`, independent of the twin's Rust code) and compares it with the run's other
files: `/scan` with `scans.jsonl` (same stamps, same ranges), `/odom` with `odometry.tum`,
`/ground_truth` with `truth.tum`, `/estimate` with `estimate.tum` when there is one.

Usage: read_run_mcap.py RUN_DIR. Prints one JSON object of counts; exits 1 naming the first
difference.
"""
import json
import math
import sys
from pathlib import Path

from mcap_ros2.reader import read_ros2_messages


def fail(what):
    print(f"run.mcap: {what}", file=sys.stderr)
    sys.exit(1)


def stamp_ns(header_stamp):
    return header_stamp.sec * 1_000_000_000 + header_stamp.nanosec


def tum(path):
    rows = []
    for line in path.read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        t, x, y, _z, qx, qy, qz, qw = map(float, line.split())
        rows.append((round(t * 1e9), x, y, 2.0 * math.atan2(qz, qw)))
    return rows


def yaw(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def rotate(q, v):
    x, y, z, _ = qmul(qmul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)


def as_pair(transform):
    t, r = transform.translation, transform.rotation
    return (t.x, t.y, t.z), (r.x, r.y, r.z, r.w)


def compose(a, b):
    (ta, qa), (tb, qb) = a, b
    moved = rotate(qa, tb)
    return tuple(ta[i] + moved[i] for i in range(3)), qmul(qa, qb)


def compare_poses(topic, got, want):
    if len(got) != len(want):
        fail(f"{topic}: {len(got)} messages, the TUM file has {len(want)} poses")
    for k, ((t, x, y, th), (t2, x2, y2, th2)) in enumerate(zip(got, want)):
        dth = math.remainder(th - th2, math.tau)
        # TUM keeps 6 decimals of metres and 9 of the quaternion; stamps 9 decimals of seconds.
        if abs(t - t2) > 1 or abs(x - x2) > 1e-6 or abs(y - y2) > 1e-6 or abs(dth) > 1e-7:
            fail(f"{topic}[{k}]: ({t}, {x}, {y}, {th}) against the TUM file's ({t2}, {x2}, {y2}, {th2})")


def main(run):
    run = Path(run)
    by_topic = {}
    schemas = {}
    for m in read_ros2_messages(str(run / "run.mcap")):
        by_topic.setdefault(m.channel.topic, []).append(m)
        schemas[m.channel.topic] = m.schema.name
        if m.log_time_ns != m.publish_time_ns:
            fail(f"{m.channel.topic}: log time {m.log_time_ns} != publish time {m.publish_time_ns}")

    lines = [json.loads(l) for l in (run / "scans.jsonl").read_text().splitlines() if l.strip()]
    scans = by_topic.get("/scan", [])
    if len(scans) != len(lines):
        fail(f"/scan: {len(scans)} messages, scans.jsonl has {len(lines)} lines")
    for k, (m, line) in enumerate(zip(scans, lines)):
        msg = m.ros_msg
        t = stamp_ns(msg.header.stamp)
        if abs(t - round(line["t"] * 1e9)) > 1 or t != m.log_time_ns:
            fail(f"/scan[{k}]: stamp {t} ns, log time {m.log_time_ns}, scans.jsonl t = {line['t']}")
        if msg.header.frame_id != "laser":
            fail(f"/scan[{k}]: frame {msg.header.frame_id!r}")
        if len(msg.ranges) != len(line["ranges"]):
            fail(f"/scan[{k}]: {len(msg.ranges)} ranges, scans.jsonl {len(line['ranges'])}")
        if abs(msg.angle_min - line["angle_min"]) > 1e-6 or abs(msg.angle_increment - line["angle_increment"]) > 1e-6:
            fail(f"/scan[{k}]: angles differ")
        for i, (r, want) in enumerate(zip(msg.ranges, line["ranges"])):
            if want >= line["range_max"]:
                if not (math.isinf(r) and r > 0):
                    fail(f"/scan[{k}].ranges[{i}] = {r}: expected +inf (no return)")
            elif abs(r - want) > 6e-8 * want:  # float32 rounds to half a unit in the last place
                fail(f"/scan[{k}].ranges[{i}] = {r}, scans.jsonl {want}")

    def poses(topic, get):
        out = []
        for m in by_topic.get(topic, []):
            t, pose = get(m.ros_msg)
            out.append((t, pose.position.x, pose.position.y, yaw(pose.orientation)))
        return out

    compare_poses("/odom", poses("/odom", lambda o: (stamp_ns(o.header.stamp), o.pose.pose)), tum(run / "odometry.tum"))
    has_truth = (run / "truth.tum").exists()  # the twin's; a drive on a robot has none
    if has_truth:
        compare_poses("/ground_truth", poses("/ground_truth", lambda o: (stamp_ns(o.header.stamp), o.pose)), tum(run / "truth.tum"))
    elif "/ground_truth" in by_topic:
        fail("/ground_truth recorded without a truth.tum beside it")
    if (run / "estimate.tum").exists():
        compare_poses("/estimate", poses("/estimate", lambda o: (stamp_ns(o.header.stamp), o.pose)), tum(run / "estimate.tum"))

    # /tf: odom -> base_link at every scan; map -> odom composes with it to the truth.
    truth = tum(run / "truth.tum") if has_truth else None
    odometry = tum(run / "odometry.tum")
    tfs = by_topic.get("/tf", [])
    if len(tfs) != len(scans):
        fail(f"/tf: {len(tfs)} messages for {len(scans)} scans")
    for k, m in enumerate(tfs):
        frames = {(t.header.frame_id, t.child_frame_id): t.transform for t in m.ros_msg.transforms}
        ob, mo = frames.get(("odom", "base_link")), frames.get(("map", "odom"))
        if ob is None:
            fail(f"/tf[{k}]: expected odom->base_link, got {sorted(frames)}")
        _, ox, oy, oth = odometry[k]
        if abs(ob.translation.x - ox) > 1e-6 or abs(ob.translation.y - oy) > 1e-6 or abs(math.remainder(yaw(ob.rotation) - oth, math.tau)) > 1e-7:
            fail(f"/tf[{k}]: odom->base_link differs from odometry.tum")
        if truth is None:
            continue
        if mo is None:
            fail(f"/tf[{k}]: expected map->odom (the twin's truth), got {sorted(frames)}")
        a, b = yaw(mo.rotation), yaw(ob.rotation)
        x = mo.translation.x + math.cos(a) * ob.translation.x - math.sin(a) * ob.translation.y
        y = mo.translation.y + math.sin(a) * ob.translation.x + math.cos(a) * ob.translation.y
        _, tx, ty, tth = truth[k]
        if abs(x - tx) > 1e-5 or abs(y - ty) > 1e-5 or abs(math.remainder(a + b - tth, math.tau)) > 1e-6:
            fail(f"/tf[{k}]: map->odom->base_link = ({x}, {y}) against the truth ({tx}, {ty})")
    static = by_topic.get("/tf_static", [])
    if len(static) != 1 or not any(t.child_frame_id == "laser" for t in static[0].ros_msg.transforms):
        fail("/tf_static: expected one message placing the laser")
    clock = by_topic.get("/clock", [])
    if [stamp_ns(c.ros_msg.clock) for c in clock] != [stamp_ns(s.ros_msg.header.stamp) for s in scans]:
        fail("/clock: expected one tick at each scan's stamp")

    # The laser on the pan-tilt head: base_link -> pan_link -> tilt_link (/tf) -> laser
    # (/tf_static) puts it where scans.jsonl says.
    statics = {t.child_frame_id: t for t in static[0].ros_msg.transforms}
    head_checked = 0
    for k, (m, line) in enumerate(zip(tfs, lines)):
        frames = {t.child_frame_id: t.transform for t in m.ros_msg.transforms}
        if "pan_link" not in frames or "laser_mount" not in line:
            continue
        pose = compose(compose(as_pair(frames["pan_link"]), as_pair(frames["tilt_link"])),
                       as_pair(statics["laser"].transform))
        (x, y, z), q = pose
        forward = rotate(q, (1.0, 0.0, 0.0))
        pitch_up = math.atan2(forward[2], math.hypot(forward[0], forward[1]))
        mx, my, _ = line["laser_mount"]
        if max(abs(x - mx), abs(y - my), abs(z - line["laser_z"]), abs(pitch_up - line["laser_tilt"])) > 1e-9:
            fail(f"/tf[{k}]: the laser by the head's transforms is at ({x}, {y}, {z}) pitched {pitch_up}, "
                 f"scans.jsonl says ({mx}, {my}, {line['laser_z']}) tilted {line['laser_tilt']}")
        head_checked += 1

    # The ring's reading against sonar.json.
    sonar = run / "sonar.json"
    sonar_checked = 0
    if sonar.exists():
        for reading in json.loads(sonar.read_text())["readings"]:
            msgs = by_topic.get(f"/sonar/{reading['sonar']}", [])
            if len(msgs) != 1:
                fail(f"/sonar/{reading['sonar']}: {len(msgs)} messages, expected the ring's one reading")
            r, want = msgs[0].ros_msg.range, reading["distance_m"]
            if (want is None and not math.isinf(r)) or (want is not None and abs(r - want) > 6e-8 * want):
                fail(f"/sonar/{reading['sonar']}: range {r}, sonar.json {want}")
            sonar_checked += 1

    # The 3D model's points: as many as model.ply's vertices.
    ply = run / "model.ply"
    if ply.exists():
        header = ply.read_bytes()[:400].decode("ascii", "replace")
        vertices = int(header.split("element vertex ")[1].split()[0])
        clouds = by_topic.get("/points", [])
        if len(clouds) != 1 or clouds[0].ros_msg.width * clouds[0].ros_msg.height != vertices:
            fail(f"/points: expected one cloud of model.ply's {vertices} points")
        cloud = clouds[0].ros_msg
        if len(cloud.data) != cloud.point_step * cloud.width or [f.name for f in cloud.fields] != ["x", "y", "z"]:
            fail("/points: data length or fields differ from the declared layout")

    print(json.dumps({
        "rosout": len(by_topic.get("/rosout", [])),
        "head_transforms_checked": head_checked,
        "sonar_checked": sonar_checked,
        "messages": sum(len(v) for v in by_topic.values()),
        "topics": {t: {"type": schemas[t], "count": len(v)} for t, v in sorted(by_topic.items())},
    }, sort_keys=True))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        fail("usage: read_run_mcap.py RUN_DIR")
    main(sys.argv[1])
