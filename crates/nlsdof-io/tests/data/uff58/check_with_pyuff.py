# Run: NLSDOF_PYUFF_PYTHON=/tmp/uffv/bin/python cargo test --release -p nlsdof-io --test uff58 pyuff
#      (venv: python3 -m venv /tmp/uffv && /tmp/uffv/bin/pip install pyuff==2.5.8 numpy)
"""Reads universal files written by nlsdof (crates/nlsdof-io/src/uff58.rs)
with pyuff and checks that pyuff reads what nlsdof reads.

Usage: check_with_pyuff.py FILE...

Each FILE comes with FILE.json, written by the Rust test
`pyuff_reads_our_files_as_we_do`: a list with one dict a dataset 58, in the
keys of pyuff's dict, floats as shortest round-trip strings. Every key and
every value must match what pyuff 2.5.8 reads (floats exactly), both with
read_sets() and with read_sets(header_only=True). Exits 1 on the first
mismatch, naming file, set and key.
"""

import json
import math
import sys

import numpy as np
import pyuff

FLOAT_KEYS = {"abscissa_min", "abscissa_inc", "z_axis_value", "x", "data"}


def fail(msg):
    print("MISMATCH: " + msg, file=sys.stderr)
    sys.exit(1)


def same_float(want, have):
    w = float(want)
    h = float(have)
    return (math.isnan(w) and math.isnan(h)) or (w == h and math.copysign(1, w) == math.copysign(1, h))


def compare(name, k, key, want, have, how=""):
    where = f"{name} set {k} {key}{how}"
    if key in FLOAT_KEYS:
        if isinstance(want, list):
            have = np.asarray(have)
            if len(want) != len(have):
                fail(f"{where}: {len(want)} values expected, pyuff reads {len(have)}")
            for i, (w, h) in enumerate(zip(want, have)):
                if isinstance(w, list):
                    ok = same_float(w[0], h.real) and same_float(w[1], h.imag)
                else:
                    ok = not np.iscomplexobj(have) and same_float(w, h)
                if not ok:
                    fail(f"{where}[{i}]: expected {w}, pyuff reads {h!r}")
        elif not same_float(want, have):
            fail(f"{where}: expected {want}, pyuff reads {have!r}")
    elif want != have:
        fail(f"{where}: expected {want!r}, pyuff reads {have!r}")


def check(name):
    want = json.load(open(name + ".json"))
    u = pyuff.UFF(name)
    n = u.get_n_sets()
    if n != len(want):
        fail(f"{name}: {len(want)} datasets expected, pyuff finds {n}")
    for k in range(n):
        full = u.read_sets(k)
        head = u.read_sets(k, header_only=True)
        w = want[k]
        for key in w:
            if key not in full:
                fail(f"{name} set {k}: pyuff has no {key}")
            compare(name, k, key, w[key], full[key])
            if key not in ("x", "data"):
                compare(name, k, key, w[key], head[key], " (header only)")
        extra = set(full) - set(w)
        if extra:
            fail(f"{name} set {k}: pyuff reads keys not expected: {sorted(extra)}")
    return n


def main(files):
    if not files:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sets = sum(check(f) for f in files)
    print(f"pyuff {pyuff.__version__} read {len(files)} files ({sets} datasets) as nlsdof reads them")


if __name__ == "__main__":
    main(sys.argv[1:])
