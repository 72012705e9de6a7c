#!/usr/bin/env python3
"""Compare two output directories of scripts/checks/identity.sh number by number.

usage: python3 scripts/checks/identity_compare.py OLD NEW [--rtol 1e-9] [--atol 1e-12] [--show 20]

Files must have the same names and the same text once numbers are taken out. Each pair of
numbers must agree to rtol relative to the larger of the two, or to atol absolute (values
that are roundoff around zero, such as a velocity of 1e-17 at rest). Binary files (MCAP, PNG)
must be identical. Prints every differing number up to --show, the largest relative difference,
and exits 1 when anything is out of tolerance.

Why: a change that is exact in arithmetic but rounds differently (another sine, another order
of a sum) cannot be checked with diff -r; issue 40 asks for outputs identical to 1e-9 relative.
"""
import argparse
import os
import re
import sys

NUM = re.compile(rb"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def split(data):
    """The text with numbers replaced by a marker, and the numbers."""
    nums = [m.group(0) for m in NUM.finditer(data)]
    return NUM.sub(b"#", data), nums


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rtol", type=float, default=1e-9)
    ap.add_argument("--atol", type=float, default=1e-12)
    ap.add_argument("--show", type=int, default=20)
    a = ap.parse_args()
    bad, shown, worst, worst_at, files, numbers = 0, 0, 0.0, "", 0, 0
    names = set()
    for root in (a.old, a.new):
        for d, _, fs in os.walk(root):
            for f in fs:
                names.add(os.path.relpath(os.path.join(d, f), root))
    for name in sorted(names):
        p, q = os.path.join(a.old, name), os.path.join(a.new, name)
        if not (os.path.exists(p) and os.path.exists(q)):
            print(f"{name}: only in one directory")
            bad += 1
            continue
        x, y = open(p, "rb").read(), open(q, "rb").read()
        files += 1
        if x == y:
            continue
        if name.endswith((".mcap", ".png")):
            print(f"{name}: binary files differ")
            bad += 1
            continue
        (tx, nx), (ty, ny) = split(x), split(y)
        if tx != ty or len(nx) != len(ny):
            print(f"{name}: text differs apart from numbers")
            bad += 1
            continue
        for u, v in zip(nx, ny):
            if u == v:
                continue
            numbers += 1
            fu, fv = float(u), float(v)
            d = abs(fu - fv)
            r = d / max(abs(fu), abs(fv))
            if d > a.atol and r > worst:
                worst, worst_at = r, f"{name}: {u.decode()} -> {v.decode()}"
            if d > a.atol and r > a.rtol:
                bad += 1
                if shown < a.show:
                    print(f"{name}: {u.decode()} -> {v.decode()} (relative {r:.2e})")
                    shown += 1
    print(f"{files} files, {numbers} numbers differ, largest relative difference above atol "
          f"{worst:.2e} ({worst_at}); {bad} out of tolerance (rtol {a.rtol:g}, atol {a.atol:g})")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
