"""Seeds of the structure-aware HDF5 targets (fuzz/fuzz_targets/{hdf5,pickle}_structured.rs).

Written with h5py 3.16 and numpy (the venv of scripts/fixtures/make_budget_h5.py); run from the repo root:
    /tmp/venv-rigid/bin/python fuzz/seeds/make_seeds.py
- sleap_*.h5: small SLEAP analysis files (tracks[2][2][3][40], node_names, track_names,
  track_occupancy) stored contiguous, chunked with deflate + shuffle, Fletcher-32, scale-offset,
  LZF, and one with variable-length names;
- dlc_pickle_slot.h5: the repo's 12-column DeepLabCut table
  (tests/data/dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5) with its
  values_block_0_kind attribute rewritten as a 60,000-byte fixed string of '@', the slot
  pickle_structured writes its pickles into (NUL padded, as PyTables' strings are).
"""

import shutil

import h5py
import numpy as np

OUT = "fuzz/seeds/"
rng = np.random.default_rng(1)


def sleap(path, dtype="f4", **kw):
    with h5py.File(OUT + path, "w") as f:
        t = rng.normal(100, 20, size=(2, 2, 3, 40)).astype(dtype)
        t[0, :, 1, 5:9] = np.nan
        f.create_dataset("tracks", data=t, **kw)
        f.create_dataset("node_names", data=np.array([b"slider", b"bob", b"tail"], dtype="S"))
        f.create_dataset("track_names", data=np.array([b"a", b"b"], dtype="S"))
        f.create_dataset("track_occupancy", data=np.ones((40, 2), dtype="u1"))


sleap("sleap_contig_f4.h5")
sleap("sleap_chunk_gzip_shuffle.h5", chunks=(1, 2, 3, 10), compression="gzip", shuffle=True)
sleap("sleap_chunk_fletcher_f8.h5", dtype="f8", chunks=(1, 1, 3, 16), fletcher32=True)
sleap("sleap_scaleoffset.h5", dtype="f8", chunks=(2, 2, 3, 20), scaleoffset=3)
sleap("sleap_lzf.h5", chunks=(2, 2, 3, 40), compression="lzf")
with h5py.File(OUT + "sleap_vlen_names.h5", "w") as f:
    f.create_dataset("tracks", data=rng.normal(size=(1, 2, 2, 10)))
    f.create_dataset("node_names", data=np.array(["slider", "bob"], dtype=h5py.string_dtype()))
    f.attrs["note"] = "x" * 100

slot = OUT + "dlc_pickle_slot.h5"
shutil.copy("tests/data/dlc_reachingvideo1shortDLC_resnet50_TESTNov4shuffle1_10.h5", slot)
with h5py.File(slot, "r+") as f:
    t = f["df_with_missing/table"]
    del t.attrs["values_block_0_kind"]
    t.attrs.create("values_block_0_kind", np.array(b"@" * 60000, dtype="S60000"))
