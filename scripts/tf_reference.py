"""Positions of two /tf frames composed to their tree's root, decoded with the official
mcap-ros2-support Python package and composed here with numpy: the independent reference
tests/it/real_files.rs compares appell's own CDR reader and tf composition against.

    python3 scripts/tf_reference.py tests/data/mcap_ros2_evo_nav2_turtlebot_tf.mcap \
        base_link front_caster_link > tests/data/mcap_ros2_evo_nav2_turtlebot_tf.reference.csv

At every stamp of a dynamic (/tf) transform, after applying every transform with that stamp,
each frame whose chain reaches the root it has in the whole recording's tree is placed;
/tf_static transforms hold for the whole recording. Output: t (s from the first row), then x,
y of each frame in the root frame.
"""
import sys

import numpy as np
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

path, a, b = sys.argv[1:4]


def rotate(q, v):
    x, y, z, w = q
    n = np.sqrt(x * x + y * y + z * z + w * w)
    u = np.array([x, y, z]) / n
    w = w / n
    c = np.cross(u, v)
    return v + 2 * (w * c + np.cross(u, c))


static, dynamic = {}, []
with open(path, "rb") as f:
    reader = make_reader(f, decoder_factories=[DecoderFactory()])
    for schema, channel, message, msg in reader.iter_decoded_messages(topics=["/tf", "/tf_static"]):
        for t in msg.transforms:
            rec = (
                t.header.stamp.sec * 10**9 + t.header.stamp.nanosec,
                t.header.frame_id,
                t.child_frame_id,
                np.array([t.transform.translation.x, t.transform.translation.y, t.transform.translation.z]),
                (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z, t.transform.rotation.w),
            )
            if channel.topic == "/tf_static":
                static[rec[2]] = rec[1:]
            else:
                dynamic.append(rec)
parent = {}
for r in list(static.values()):
    parent[r[1]] = r[0]
for r in dynamic:
    parent[r[2]] = r[1]


def root(f):
    while f in parent:
        f = parent[f]
    return f


current = dict(static)
dynamic.sort(key=lambda r: r[0])
rows = []
i = 0
while i < len(dynamic):
    ns = dynamic[i][0]
    while i < len(dynamic) and dynamic[i][0] == ns:
        r = dynamic[i]
        current[r[2]] = r[1:]
        i += 1
    out = []
    for frame in (a, b):
        p, f = np.zeros(3), frame
        while f in current:
            par, _, tr, q = current[f]
            p = rotate(q, p) + tr
            f = par
        out.append(p if f == root(frame) else None)
    if out[0] is not None or out[1] is not None:
        rows.append((ns, out))
print(f"t,{a}_x,{a}_y,{b}_x,{b}_y")
t0 = rows[0][0]
for ns, (p, q) in rows:
    cell = lambda v: "," if v is None else f"{float(v[0])!r},{float(v[1])!r}"
    print(f"{(ns - t0) / 1e9!r},{cell(p)},{cell(q)}")
