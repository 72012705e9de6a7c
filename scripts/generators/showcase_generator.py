#!/usr/bin/env python3
"""One release of a point-pendulum rig, written as four tracking tools write their files.

Purpose
-------
The README's and docs' examples need recordings that look like a lab's: camera noise, dropped
frames, a few mis-tracked points, pixels on a slightly rotated camera, a motion-capture take with
unlabeled markers and a gap. This script simulates ONE release with scripts/generators/rigid_generator.py's
Newton-Euler hybrid loop (its own equations, independent of the Rust code; a point pendulum is
its rig with rod_mass = 0 and bob_radius = 0) and films it four times:

  showcase_dlc.csv           DeepLabCut CSV: 3 header rows (scorer, bodyparts, coords), x, y,
                             likelihood per bodypart (slider, bob, rail_end: a fixed marker at
                             the rail's end), frame index, no time; pixels, origin top left, y
                             down; 100 fps; 1240 px/m; camera rolled 1.8 deg from the rail;
                             0.4 px noise; values as float32 (as DeepLabCut's arrays are).
  showcase_sleap.csv         SLEAP analysis CSV: track,frame_idx,instance.score, NODE.x, NODE.y,
                             NODE.score (nodes slider, bob; track track_0); 200 fps; 960 px/m;
                             camera rolled -1.2 deg; 0.35 px noise; frames without a prediction
                             are left out, a node not found is three empty cells.
  showcase_motive.csv        OptiTrack Motive 1.23 CSV: metadata row, blank row, Type/Name/ID/
                             Position rows, Frame,Time (Seconds),X,Y,Z; millimetres, Y up
                             (Motive's ground plane), 240 Hz, Time rounded to the millisecond;
                             the rail along Motive's X (yawed 0.4 deg towards Z), the rig in the
                             vertical XY plane 1.1 m above the floor; markers on the front faces
                             (15 mm towards the cameras, +Z); unlabeled markers: the slider
                             "Unlabeled 1001", the bob "Unlabeled 1002", a marker on the rail's
                             end "Unlabeled 1003"; the bob is occluded for 5 frames and comes back
                             as "Unlabeled 1004" (as Motive renames a marker it loses); 0.15 mm
                             noise.
  showcase_tracker_slider.txt, showcase_tracker_bob.txt
                             Tracker exports (File > Export > Data), one per track, English
                             locale, CRLF: the track name (Tracker's default names mass_A, mass_B),
                             "t x y", tab-separated, full double digits; 120 fps; metres, y up,
                             axes set by hand 0.3 deg off the rail with the origin a few mm from
                             the slider's start; 0.3 mm noise; the autotracker missed the bob in
                             two frames (empty cells); the two tracks' times are accumulated
                             differently in the last digits, as two exports of one video are.

Every camera starts at a random phase within its first frame after the release (the first
frame is not the release instant). Mis-tracks planted (listed in truth.json with their frames):
DeepLabCut: 3 slider and 4 bob frames with likelihood < 0.1 at garbage positions (read as
missing under the default --min-likelihood 0.6), and 2 bob frames with likelihood 0.7-0.8 that
jumped 14-22 px to a wrong feature, 1 slider frame 9 px off; SLEAP: 2 bob frames 15-20 px off;
Motive: none (a ghost-free take); Tracker: 1 bob frame 6 mm off (an autotracker slip).

The rig file a lab would type (showcase_rig.toml) has the rod measured 1 mm long, the masses 2 %
off (slider heavy, bob light), with the ruler's and the scale's standard deviations in the
*_sd keys; truth.json has the true values, the release, the events and the planted mis-tracks.

Run (outside CI; Python 3 with numpy and scipy)
    python3 -m venv /tmp/venv-show && /tmp/venv-show/bin/pip install numpy scipy
    /tmp/venv-show/bin/python scripts/generators/showcase_generator.py --out tests/data/showcase
Options: --check (energy balance of the simulated release: the friction work against the
loss), --seed N (another draw of noise and mis-tracks, for a coverage sweep; default 2).
"""

import argparse
import json
import math
import os
import platform
import sys

import numpy as np
import scipy

sys.dont_write_bytecode = True  # leave no __pycache__ in scripts/
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rigid_generator as rg  # noqa: E402

# The rig (point pendulum) and the release.
M1, M2, L_ROD, G, MU = 0.30, 0.15, 0.25, 9.81, 0.18
RELEASE_FROM_HANGING = 1.1  # rad, bob towards +x, at rest
DURATION = 2.5
SEED = 2  # the committed draw (see tests/data/showcase/README.md)

# What the lab measured: the rod 1 mm long, the slider 2 % heavy, the bob 2 % light.
MEASURED = dict(rod_length=0.251, slider_mass=0.306, bob_mass=0.147)
MEASURED_SD = dict(rod_length_sd=0.001, slider_mass_sd=0.006, bob_mass_sd=0.003)


def simulate():
    rig = rg.Rig(M1, M2, L_ROD, 0.0, 0.0, G, MU)
    y0 = (0.0, math.pi / 2 - RELEASE_FROM_HANGING, 0.0, 0.0)
    segs, evs, _ = rg.simulate(rig, y0, DURATION + 0.05)
    return rig, y0, segs, evs


def markers(rig, segs, ts):
    """Rail frame, y up, metres: slider (x, 0), bob (x + l cos th, -l sin th)."""
    Y = rg.sample(segs, ts)
    x, th = Y[:, 0], Y[:, 1]
    slider = np.column_stack([x, np.zeros_like(x)])
    bob = np.column_stack([x + rig.l * np.cos(th), -rig.l * np.sin(th)])
    return slider, bob, Y


def frame_times(rng, fps):
    """Frame times from the release: a random phase within the first frame."""
    phase = rng.uniform(0.1, 0.9) / fps
    n = int(math.floor((DURATION - phase) * fps)) + 1
    return phase + np.arange(n) / fps, phase


def f32(v):
    """A float32 value written as Python writes the float64 it converts to (DeepLabCut, SLEAP)."""
    return repr(float(np.float32(v)))


def to_image(p, origin_px, px_per_m, roll_deg):
    """Rail-frame metres (y up) to pixels (y down, origin top left) on a camera rolled by
    roll_deg: the rail appears rotated by roll_deg counter-clockwise in the picture."""
    a = math.radians(roll_deg)
    c, s = math.cos(a), math.sin(a)
    xr = c * p[:, 0] - s * p[:, 1]
    yr = s * p[:, 0] + c * p[:, 1]
    return np.column_stack([origin_px[0] + px_per_m * xr, origin_px[1] - px_per_m * yr])


def film(rng, rig, segs, fps, px_per_m, roll_deg, noise_px, origin_px):
    """A video camera's view of the release: the first frame's phase, the frame count, and
    the slider's and bob's pixels with the tracker's noise."""
    ts, phase = frame_times(rng, fps)
    slider, bob, _ = markers(rig, segs, ts)
    n = len(ts)
    sl = to_image(slider, origin_px, px_per_m, roll_deg) + rng.normal(0, noise_px, (n, 2))
    bo = to_image(bob, origin_px, px_per_m, roll_deg) + rng.normal(0, noise_px, (n, 2))
    return phase, n, sl, bo


def write_dlc(path, rng, rig, segs):
    fps, k, roll, noise = 100.0, 1240.0, 1.8, 0.4
    origin = (612.0, 287.0)
    phase, n, sl, bo = film(rng, rig, segs, fps, k, roll, noise, origin)
    rail_end = to_image(np.array([[0.42, 0.0]]), origin, k, roll)[0]
    re = rail_end + rng.normal(0, noise, (n, 2))
    # Likelihoods of a well-trained network: mostly above 0.95.
    lik = np.clip(1.0 - np.abs(rng.normal(0, 0.02, (n, 3))), 0.0, 0.9999)
    planted = dict(low_likelihood=dict(slider=[], bob=[]), mistracked=dict(slider=[], bob=[]))
    frames = rng.choice(np.arange(5, n - 5), size=10, replace=False)
    low_s, low_b, jump_b, jump_s = frames[:3], frames[3:7], frames[7:9], frames[9:10]
    for i in low_s:
        sl[i] = rng.uniform([0, 0], [1280, 1024])
        lik[i, 0] = rng.uniform(0.005, 0.09)
        planted["low_likelihood"]["slider"].append(int(i))
    for i in low_b:
        bo[i] = rng.uniform([0, 0], [1280, 1024])
        lik[i, 1] = rng.uniform(0.005, 0.09)
        planted["low_likelihood"]["bob"].append(int(i))
    for i in jump_b:
        ang = rng.uniform(0, 2 * math.pi)
        bo[i] += rng.uniform(14, 22) * np.array([math.cos(ang), math.sin(ang)])
        lik[i, 1] = rng.uniform(0.7, 0.8)
        planted["mistracked"]["bob"].append(int(i))
    for i in jump_s:
        sl[i, 0] += 9.0
        lik[i, 0] = rng.uniform(0.7, 0.8)
        planted["mistracked"]["slider"].append(int(i))
    scorer = "DLC_resnet50_pendulumrailNov14shuffle1_200000"
    with open(path, "w", newline="\n") as fh:
        fh.write("scorer," + ",".join([scorer] * 9) + "\n")
        fh.write("bodyparts," + ",".join(b for b in ["slider", "bob", "rail_end"] for _ in range(3))
                 + "\n")
        fh.write("coords," + ",".join(["x", "y", "likelihood"] * 3) + "\n")
        for i in range(n):
            cells = []
            for j, p in enumerate([sl[i], bo[i], re[i]]):
                cells += [f32(p[0]), f32(p[1]), f32(lik[i, j])]
            fh.write(f"{i}," + ",".join(cells) + "\n")
    return dict(file=os.path.basename(path), fps=fps, first_frame_after_release_s=phase,
                frames=n, px_per_m=k, camera_roll_deg=roll, noise_px=noise,
                noise_m=noise / k, image_origin_of_rail_px=origin,
                planted={k2: {m: sorted(v) for m, v in d.items()} for k2, d in planted.items()})


def write_sleap(path, rng, rig, segs):
    fps, k, roll, noise = 200.0, 960.0, -1.2, 0.35
    origin = (455.0, 198.0)
    phase, n, sl, bo = film(rng, rig, segs, fps, k, roll, noise, origin)
    score = np.clip(1.0 - np.abs(rng.normal(0, 0.04, (n, 2))), 0.0, 1.0)
    picks = rng.choice(np.arange(5, n - 5), size=12, replace=False)
    no_pred = sorted(int(i) for i in picks[:4])   # frames without any prediction: no row
    no_slider = sorted(int(i) for i in picks[4:7])
    no_bob = sorted(int(i) for i in picks[7:10])
    jumps = sorted(int(i) for i in picks[10:12])
    for i in jumps:
        ang = rng.uniform(0, 2 * math.pi)
        bo[i] += rng.uniform(15, 20) * np.array([math.cos(ang), math.sin(ang)])
        score[i, 1] = rng.uniform(0.4, 0.6)
    with open(path, "w", newline="\n") as fh:
        fh.write("track,frame_idx,instance.score,slider.x,slider.y,slider.score,"
                 "bob.x,bob.y,bob.score\n")
        for i in range(n):
            if i in no_pred:
                continue
            cells = ["track_0", str(i), f32(rng.uniform(0.85, 0.99))]
            for j, (p, gone) in enumerate([(sl[i], no_slider), (bo[i], no_bob)]):
                cells += ["", "", ""] if i in gone else [f32(p[0]), f32(p[1]), f32(score[i, j])]
            fh.write(",".join(cells) + "\n")
    return dict(file=os.path.basename(path), fps=fps, first_frame_after_release_s=phase,
                frames=n, px_per_m=k, camera_roll_deg=roll, noise_px=noise, noise_m=noise / k,
                image_origin_of_rail_px=origin,
                planted=dict(frames_without_prediction=no_pred,
                             missing_node=dict(slider=no_slider, bob=no_bob),
                             mistracked=dict(slider=[], bob=jumps)))


def write_motive(path, rng, rig, segs):
    fps, noise_mm = 240.0, 0.15
    ts, phase = frame_times(rng, fps)
    slider, bob, _ = markers(rig, segs, ts)
    n = len(ts)
    yaw = math.radians(0.4)
    origin = np.array([-312.4, 1104.7, -86.3])  # mm, Motive's global frame, Y up

    def world(p, front=15.0):
        # rail x along Motive's X yawed towards Z; rail-frame y up is Motive's Y; the markers
        # sit on the parts' front faces, `front` mm towards the cameras (+Z).
        X = origin[0] + 1000.0 * p[:, 0] * math.cos(yaw)
        Z = origin[2] + 1000.0 * p[:, 0] * math.sin(yaw) + front
        Y = origin[1] + 1000.0 * p[:, 1]
        return np.column_stack([X, Y, Z]) + rng.normal(0, noise_mm, (len(p), 3))

    s3, b3 = world(slider), world(bob)
    rail_end = world(np.array([[0.42, 0.0]] * n), front=8.0)
    gap_start = int(rng.integers(int(0.9 * fps), int(1.6 * fps)))
    gap = list(range(gap_start, gap_start + 5))
    cols = [("Unlabeled 1001", s3, range(n)), ("Unlabeled 1002", b3, range(gap_start)),
            ("Unlabeled 1003", rail_end, range(n)),
            ("Unlabeled 1004", b3, range(gap_start + 5, n))]
    ids = ["1A2B9C1155D1E11EF", "2A2B9C1155D1E11EF", "3A2B9C1155D1E11EF", "4A2B9C1155D1E11EF"]
    meta = ["Format Version", "1.23", "Take Name", "rail_release_03", "Take Notes", "",
            "Capture Frame Rate", f"{fps:.6f}", "Export Frame Rate", f"{fps:.6f}",
            "Capture Start Time", "2026-11-14 02.41.07.512 PM", "Capture Start Frame", "103244",
            "Total Frames in Take", str(n), "Total Exported Frames", str(n),
            "Rotation Type", "Quaternion", "Length Units", "Millimeters",
            "Coordinate Space", "Global"]
    with open(path, "w", newline="\n") as fh:
        fh.write(",".join(meta) + "\n\n")
        fh.write(",Type," + ",".join(["Marker"] * 3 * len(cols)) + "\n")
        fh.write(",Name," + ",".join(c[0] for c in cols for _ in range(3)) + "\n")
        fh.write(",ID," + ",".join(f'"{i}"' for i in ids for _ in range(3)) + "\n")
        fh.write(",," + ",".join(["Position"] * 3 * len(cols)) + "\n")
        fh.write("Frame,Time (Seconds)," + ",".join(["X", "Y", "Z"] * len(cols)) + "\n")
        for i in range(n):
            cells = [str(i), f"{round(i / fps, 3):.6f}"]
            for _, data, rows in cols:
                cells += ([f"{v:.6f}" for v in data[i]] if i in rows else ["", "", ""])
            fh.write(",".join(cells) + "\n")
    return dict(file=os.path.basename(path), fps=fps, first_frame_after_release_s=phase,
                frames=n, noise_mm=noise_mm, noise_m=noise_mm / 1000.0, rail_yaw_deg=0.4,
                rail_origin_mm=origin.tolist(), marker_front_offset_mm=15.0,
                planted=dict(bob_gap_frames=gap, bob_renamed_after_gap="Unlabeled 1004",
                             mistracked=dict(slider=[], bob=[])))


def write_tracker(path_s, path_b, rng, rig, segs):
    fps, noise = 120.0, 0.0003
    ts, phase = frame_times(rng, fps)
    slider, bob, _ = markers(rig, segs, ts)
    n = len(ts)
    a = math.radians(0.3)
    off = np.array([0.0042, -0.0017])

    def axes(p):
        # The user's axes: rotated 0.3 deg from the rail, origin near the slider's start.
        c, s = math.cos(a), math.sin(a)
        q = p - off
        return np.column_stack([c * q[:, 0] - s * q[:, 1], s * q[:, 0] + c * q[:, 1]])

    sl = axes(slider) + rng.normal(0, noise, (n, 2))
    bo = axes(bob) + rng.normal(0, noise, (n, 2))
    picks = rng.choice(np.arange(5, n - 5), size=3, replace=False)
    missed = sorted(int(i) for i in picks[:2])
    slip = int(picks[2])
    ang = rng.uniform(0, 2 * math.pi)
    bo[slip] += 0.006 * np.array([math.cos(ang), math.sin(ang)])
    # Two exports of one video: times summed frame by frame, and frame x duration.
    dt = 1.0 / fps
    t_sum = np.concatenate([[0.0], np.cumsum(np.full(n - 1, dt))])
    t_mul = np.arange(n) * (1000.0 / fps) / 1000.0
    for path, name, data, t, gone in [(path_s, "mass_A", sl, t_sum, []),
                                      (path_b, "mass_B", bo, t_mul, missed)]:
        with open(path, "w", newline="\r\n") as fh:  # a Windows machine's export
            fh.write(f"{name}\nt\tx\ty\n")
            for i in range(n):
                xy = "\t" if i in gone else f"{float(data[i, 0])!r}\t{float(data[i, 1])!r}"
                fh.write(f"{float(t[i])!r}\t{xy}\n")
    return dict(files=[os.path.basename(path_s), os.path.basename(path_b)], fps=fps,
                first_frame_after_release_s=phase, frames=n, noise_m=noise,
                axes_rotation_deg=0.3, axes_origin_in_rail_frame_m=off.tolist(),
                planted=dict(bob_missed_frames=missed, mistracked=dict(slider=[], bob=[slip])))


def write_rig(path):
    with open(path, "w") as fh:
        fh.write("# The rig of the showcase recordings as a lab measured it: the rod with a ruler\n"
                 "# (1 mm off), the masses on a kitchen scale (2 % off); the true values are in\n"
                 "# truth.json (made by scripts/generators/showcase_generator.py). mu is the unknown.\n")
        fh.write("[rig]\n")
        fh.write(f"slider_mass = {MEASURED['slider_mass']}   # kg, the slider with its pivot\n")
        fh.write(f"bob_mass = {MEASURED['bob_mass']}      # kg\n")
        fh.write(f"rod_length = {MEASURED['rod_length']}    # m, pivot axis to the bob's centre\n")
        fh.write("gravity = 9.81\n")
        fh.write("rod_mass = 0.0      # a thin wire: a point pendulum\n")
        fh.write("bob_radius = 0.0\n")
        fh.write(f"rod_length_sd = {MEASURED_SD['rod_length_sd']}   # m, a ruler\n")
        fh.write(f"slider_mass_sd = {MEASURED_SD['slider_mass_sd']}  # kg, a kitchen scale (2 %)\n")
        fh.write(f"bob_mass_sd = {MEASURED_SD['bob_mass_sd']}\n")


def energy_check(rig, y0, segs, evs):
    """Energy lost equals the friction work (W' = F x'), to the integrator's tolerance."""
    ts = np.linspace(0.0, DURATION, 2001)
    Y = rg.sample(segs, ts)
    e = np.array([rg.energy(rig, y) for y in Y])
    err = np.max(np.abs(e - e[0] - Y[:, 4]))
    return float(err)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--check", action="store_true")
    ap.add_argument("--seed", type=int, default=SEED,
                    help="noise and mis-track draw (the committed files: the default)")
    args = ap.parse_args(argv)
    rig, y0, segs, evs = simulate()
    err = energy_check(rig, y0, segs, evs)
    print(f"energy balance error {err:.2e} J over {DURATION} s")
    if args.check and err > 1e-8:
        return 1
    for e in evs:
        print(f"  t = {e['t']:.6f} s  {e['kind']}")
    os.makedirs(args.out, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    o = lambda name: os.path.join(args.out, name)  # noqa: E731
    files = dict(
        dlc=write_dlc(o("showcase_dlc.csv"), rng, rig, segs),
        sleap=write_sleap(o("showcase_sleap.csv"), rng, rig, segs),
        motive=write_motive(o("showcase_motive.csv"), rng, rig, segs),
        tracker=write_tracker(o("showcase_tracker_slider.txt"), o("showcase_tracker_bob.txt"),
                              rng, rig, segs),
    )
    write_rig(o("showcase_rig.toml"))
    truth = dict(
        generator="scripts/generators/showcase_generator.py", seed=args.seed, python=platform.python_version(),
        numpy=np.__version__, scipy=scipy.__version__,
        solver=dict(method="DOP853", rtol=rg.RTOL, atol=rg.ATOL),
        rig=dict(slider_mass=M1, bob_mass=M2, rod_length=L_ROD, gravity=G, mu_kinetic=MU,
                 mu_static=MU, friction_law="coulomb", mass_ratio=M1 / M2,
                 mu_star=rig.mu_star),
        measured_rig=dict(MEASURED, **MEASURED_SD),
        initial=dict(zip(["x", "theta", "x_dot", "theta_dot"], y0)),
        theta_convention="docs/physics.md: from the rail's +x, y down; pi/2 hangs down",
        duration_s=DURATION, energy_balance_error_J=err,
        events=[dict(t=float(e["t"]), kind=e["kind"],
                     state=dict(zip(["x", "theta", "x_dot", "theta_dot"],
                                    [float(v) for v in e["state"]])))
                for e in evs if e["t"] <= DURATION],
        files=files,
    )
    with open(o("truth.json"), "w") as fh:
        json.dump(truth, fh, indent=2)
        fh.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
