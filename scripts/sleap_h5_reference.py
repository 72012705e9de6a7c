"""Write the values of a SLEAP analysis HDF5 file as plain CSV, read with h5py (the HDF5 C
library): the independent reference tests/it/real_files.rs compares appell's pure-Rust reader
against.

    python3 scripts/sleap_h5_reference.py tests/data/sleap_three-mice_Aeon.analysis.h5 \
        > tests/data/sleap_three-mice_Aeon.analysis.reference.csv
"""
import sys

import h5py
import numpy as np

f = h5py.File(sys.argv[1], "r")
tracks = f["tracks"][:]  # [track][xy][node][frame]
names = [n.decode() for n in f["track_names"][:]]
nodes = [n.decode() for n in f["node_names"][:]]
cols = [f"{t}/{n}" for t in names for n in nodes]
print("frame," + ",".join(f"{c}.x,{c}.y" for c in cols))
for k in range(tracks.shape[3]):
    cells = []
    for ti in range(tracks.shape[0]):
        for ni in range(tracks.shape[2]):
            x, y = tracks[ti, 0, ni, k], tracks[ti, 1, ni, k]
            cells += ["", ""] if np.isnan(x) or np.isnan(y) else [repr(float(x)), repr(float(y))]
    print(f"{k}," + ",".join(cells))
