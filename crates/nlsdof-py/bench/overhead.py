"""Python-side costs of the nlsdof module (a benchmark, not a test).

1. Call overhead of `Model.sweep` on the wing, 5 levels x 200 steps: the
   time of the Python call against the time of the same Rust computation
   (`cargo bench -p nlsdof --bench frf -- level_responses`), given here with
   --rust-us; and the fixed cost of a call that computes almost nothing.
2. Memory of `Model.simulate` on 10^6 samples: the growth of the peak RSS
   during the call, against the 16 MB of its two output arrays (the input
   is read in place).

    python overhead.py [--rust-us MICROSECONDS]
"""

import argparse
import pathlib
import timeit

import numpy as np

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]


def best(stmt, number, repeat=7):
    return min(timeit.repeat(stmt, number=number, repeat=repeat)) / number


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rust-us", type=float, help="criterion time of level_responses, us")
    args = ap.parse_args()
    wing = nlsdof.Model.from_toml(ROOT / "examples" / "har-wing.toml")
    levels = [0.41, 0.62, 0.81, 1.00, 1.23]
    f = np.array([5.2 + 0.4 * i / 199 for i in range(200)])
    t_sweep = best(lambda: wing.sweep(gamma=levels, f_hz=f), number=200)
    one = np.array([5.4])
    t_tiny = best(lambda: wing.sweep(gamma=0.41, f_hz=one), number=5000)
    print(f"Model.sweep, wing 5 x 200: {1e6 * t_sweep:.1f} us per call")
    print(f"Model.sweep, 1 level x 1 step (the fixed cost of a call): {1e6 * t_tiny:.2f} us")
    if args.rust_us:
        over = 1e6 * t_sweep - args.rust_us
        print(f"overhead against Rust {args.rust_us:.1f} us: {over:.1f} us = "
              f"{100 * over / args.rust_us:.1f} %")

    n = 1_000_000
    u = np.sin(2 * np.pi * 5.4 * np.arange(n) / 1000.0)
    wing.simulate(u[:1000], fs=1000.0)

    def status(key):  # kB, Linux
        for line in open("/proc/self/status"):
            if line.startswith(key):
                return int(line.split()[1])
        raise KeyError(key)

    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")  # the peak RSS (VmHWM) restarts from the current RSS
    before = status("VmRSS:")
    x, v = wing.simulate(u, fs=1000.0)
    peak = status("VmHWM:")
    print(f"Model.simulate, 10^6 samples: peak RSS {(peak - before) / 1024:.1f} MiB above the RSS "
          f"before the call; the two outputs are {(x.nbytes + v.nbytes) / 2**20:.1f} MiB, "
          f"the input {u.nbytes / 2**20:.1f} MiB")
    t_sim = best(lambda: wing.simulate(u, fs=1000.0), number=1, repeat=3)
    print(f"Model.simulate, 10^6 samples: {t_sim:.3f} s")


if __name__ == "__main__":
    main()
