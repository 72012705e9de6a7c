#!/usr/bin/env python3
"""Write the protobuf MCAP examples in tests/data from tests/data/markers_reference.csv.

Made with the official libraries so the reader is tested against files it did not write
(run outside CI; the generated files are committed):

    python3 -m venv /tmp/venv-proto
    /tmp/venv-proto/bin/pip install mcap mcap-protobuf-support foxglove-schemas-protobuf
    /tmp/venv-proto/bin/python scripts/make_protobuf_examples.py

Made with mcap 1.6.0, mcap-protobuf-support 0.6.0, foxglove-schemas-protobuf 0.4.0.

All 2001 frames are written. The in-message timestamp is t_ns exactly; log_time gets a
deterministic 0-499 us "transport jitter" so a reader that used log_time instead of the stamp
would fail the tests.
"""

import csv
from pathlib import Path

from foxglove_schemas_protobuf.FrameTransform_pb2 import FrameTransform
from foxglove_schemas_protobuf.Point2_pb2 import Point2
from foxglove_schemas_protobuf.PointsAnnotation_pb2 import PointsAnnotation
from mcap_protobuf.writer import Writer

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"


def frames():
    with open(DATA / "markers_reference.csv", newline="") as f:
        for i, row in enumerate(csv.DictReader(f)):
            t_ns = int(row["t_ns"])
            slider = (float(row["slider_x"]), float(row["slider_y"]))
            bob = (float(row["bob_x"]), float(row["bob_y"]))
            jitter = (i * 7919 % 500) * 1000
            yield i, t_ns, t_ns + jitter, slider, bob


def stamp(msg, t_ns):
    msg.timestamp.seconds = t_ns // 1_000_000_000
    msg.timestamp.nanos = t_ns % 1_000_000_000


def frame_transforms():
    with open(DATA / "markers_foxglove_frametransform.mcap", "wb") as out, Writer(out) as w:
        for i, t_ns, log_ns, slider, bob in frames():
            for name, (x, y) in (("slider", slider), ("bob", bob)):
                m = FrameTransform()
                stamp(m, t_ns)
                m.parent_frame_id = "rail"
                m.child_frame_id = name
                m.translation.x = x
                m.translation.y = y
                m.translation.z = 0.0
                m.rotation.w = 1.0
                w.write_message("/tf", m, log_time=log_ns, publish_time=log_ns)


def points_annotations():
    with open(DATA / "markers_foxglove_points.mcap", "wb") as out, Writer(out) as w:
        for i, t_ns, log_ns, slider, bob in frames():
            m = PointsAnnotation()
            stamp(m, t_ns)
            m.type = PointsAnnotation.POINTS
            # Identity by index: point 0 is the slider, point 1 the bob.
            m.points.extend([Point2(x=slider[0], y=slider[1]), Point2(x=bob[0], y=bob[1])])
            m.thickness = 2.0
            w.write_message("/markers/points", m, log_time=log_ns, publish_time=log_ns)


if __name__ == "__main__":
    frame_transforms()
    points_annotations()
