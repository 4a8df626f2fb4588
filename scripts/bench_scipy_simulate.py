#!/usr/bin/env python3
"""Reference timing: the nlsdof time-domain model (paper Eq 32) integrated by
scipy's solve_ivp RK45 on a recorded input, for comparison with the Rust
integrators (crates/nlsdof/benches/simulate.rs runs this script and reports
the per-sample speed ratio).

    x'' = u(t) - (c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho) / m

The input u(t) is a raw little-endian float64 file sampled at --fs Hz and is
interpolated linearly between samples (np.interp), as in the Rust reference
integrator. The state is reported at every sample time (t_eval).

Usage:
    python3 scripts/bench_scipy_simulate.py --input u.f64 --fs 2048 \
        --model 0.26699,306.7878,0.1164,85000,4.0022,0.01591,3.03099 \
        [--rtol 1e-3 --atol 1e-6] [--reference x.f64] [--repeat 1]

Prints one JSON line: samples, seconds, per_sample_s, nfev, and (with
--reference, the Rust reference displacement at the same samples) the
relative max-norm error of the scipy solution.

Requires numpy and scipy (pip install numpy scipy).
"""
import argparse
import json
import time

import numpy as np
from scipy.integrate import solve_ivp


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--input", required=True, help="raw float64 (little-endian) input acceleration samples")
    ap.add_argument("--fs", type=float, required=True, help="sampling frequency, Hz")
    ap.add_argument("--model", required=True, help="m,k,c,k_r,rho,c_e,eta (SI)")
    ap.add_argument("--rtol", type=float, default=1e-3)
    ap.add_argument("--atol", type=float, default=1e-6)
    ap.add_argument("--reference", help="raw float64 reference displacement at every sample")
    ap.add_argument("--repeat", type=int, default=1, help="runs; the fastest is reported")
    a = ap.parse_args()

    u = np.fromfile(a.input, dtype="<f8")
    n = u.size
    t = np.arange(n) / a.fs
    m, k, c, kr, rho, ce, eta = (float(v) for v in a.model.split(","))

    def rhs(tt, y):
        x, v = y
        ui = np.interp(tt, t, u)
        f = c * v + k * x
        if kr != 0.0:
            f += kr * x * abs(x) ** rho
        if ce != 0.0:
            f += ce * v * abs(v) ** eta
        return [v, ui - f / m]

    best = None
    sol = None
    for _ in range(max(1, a.repeat)):
        t0 = time.perf_counter()
        sol = solve_ivp(rhs, (t[0], t[-1]), [0.0, 0.0], method="RK45", t_eval=t, rtol=a.rtol, atol=a.atol)
        dt = time.perf_counter() - t0
        best = dt if best is None else min(best, dt)
    out = {
        "samples": int(n),
        "rtol": a.rtol,
        "atol": a.atol,
        "seconds": best,
        "per_sample_s": best / n,
        "nfev": int(sol.nfev),
        "success": bool(sol.success),
    }
    if a.reference:
        ref = np.fromfile(a.reference, dtype="<f8")
        if ref.size == n and sol.success:
            out["rel_error"] = float(np.max(np.abs(sol.y[0] - ref)) / np.max(np.abs(ref)))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
