"""Small HDF5 files that would make a reader spend without bound (issue 25): each declares far
more than it holds, or holds data that decodes far past its size. The reader must refuse each
one against its per-file budget (src/data/budget.rs) instead of allocating.

Usage: /tmp/venv-rigid/bin/python scripts/make_budget_h5.py tests/data/budget
(written with h5py 3.16.0, HDF5 2.0.0, numpy 2.4.6)."""

import os
import sys

import h5py
import numpy as np


def sleap_1e9_nodes(path):
    # SLEAP's tracks[track][xy][node][frame] declaring 10^9 nodes and no frames: no values,
    # but one series per node.
    with h5py.File(path, "w") as f:
        f.create_dataset("tracks", shape=(1, 2, 10**9, 0), dtype="f8")


def sleap_scaleoffset_1gib(path):
    # 1 GiB of float64 zeros through scale-offset then deflate: each 32 MiB chunk stores a
    # few bytes, far beyond deflate's 1032:1 alone.
    n = 1 << 25
    with h5py.File(path, "w") as f:
        ds = f.create_dataset(
            "tracks",
            shape=(1, 2, 2, n),
            dtype="f8",
            chunks=(1, 1, 1, 1 << 22),
            scaleoffset=0,
            compression="gzip",
            compression_opts=9,
        )
        zeros = np.zeros(1 << 22, dtype="f8")
        for c in range(2):
            for node in range(2):
                for k in range(0, n, 1 << 22):
                    ds[0, c, node, k : k + (1 << 22)] = zeros


def dlc_fixed_1e8_codes(path, columns=3):
    # pandas' fixed format with 10^8 one-byte codes for the first column-label level
    # (deflated, within 1032:1), each of which became a string before any check; the values
    # declare `columns` columns (and no rows).
    n = 10**8
    with h5py.File(path, "w") as f:
        g = f.create_group("df_with_missing")
        g.attrs["pandas_type"] = np.bytes_(b"frame")
        g.attrs["nblocks"] = np.int64(1)
        g.attrs["block0_items_nlevels"] = np.int64(3)
        g.create_dataset("block0_values", shape=(0, columns), dtype="f8").attrs[
            "transposed"
        ] = np.int8(1)
        for i, names in enumerate([[b"scorer"], [b"nose"], [b"x", b"y", b"likelihood"]]):
            g.create_dataset(f"block0_items_level{i}", data=np.array(names, dtype="S"))
        g.create_dataset(
            "block0_items_label0",
            data=np.zeros(n, dtype="i1"),
            chunks=(1 << 22,),
            compression="gzip",
            compression_opts=9,
        )
        g.create_dataset("block0_items_label1", data=np.zeros(3, dtype="i1"))
        g.create_dataset("block0_items_label2", data=np.arange(3, dtype="i1"))


def dlc_fixed_1e8_columns(path):
    # The same codes, the values declaring as many columns: the labels' strings (3 GB) are
    # over the budget.
    dlc_fixed_1e8_codes(path, columns=10**8)


def dlc_table_pickle_refs(path):
    # pandas' table format whose column labels (a protocol-0 pickle) are one 512 KiB string
    # referenced 131,072 times: 131,072 strings (under the string guard) but 64 GiB decoded.
    refs = 131072
    text = b"a" * (512 << 10)
    pickle = b"(lp0\nV" + text + b"\np1\na" + b"g1\na" * (refs - 1) + b"."
    with h5py.File(path, "w", libver="latest") as f:
        g = f.create_group("df_with_missing")
        g.attrs["pandas_type"] = np.bytes_(b"frame_table")
        row = np.dtype([("index", "<i8"), ("values_block_0", "<f8", (refs,))])
        t = g.create_dataset("table", shape=(0,), dtype=row)
        t.attrs["values_block_0_kind"] = np.bytes_(pickle)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "tests/data/budget"
    os.makedirs(out, exist_ok=True)
    for make in [
        sleap_1e9_nodes,
        sleap_scaleoffset_1gib,
        dlc_fixed_1e8_codes,
        dlc_fixed_1e8_columns,
        dlc_table_pickle_refs,
    ]:
        path = os.path.join(out, make.__name__ + ".h5")
        make(path)
        print(path, os.path.getsize(path))


if __name__ == "__main__":
    main()
