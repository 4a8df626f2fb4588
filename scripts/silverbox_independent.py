#!/usr/bin/env python3
"""Independent score of a Silverbox model file written by `nlsdof fit-time`
(issue 26): the model is integrated by scipy DOP853 (rtol 1e-10, atol
1e-13), which shares no code with nlsdof, on the input reconstruction the
model file states (`[signal] input_interpolation`, cubic when absent: the
4-point Lagrange cubic through samples b..b+3, b = clamp(k-1, 0, n-4), as in
crates/nlsdof-cli/tests/data/independent_fit_time.py). The integrator is
restarted at every sample, so the kinks of the piecewise input are step
boundaries.

Each test set starts from the initial state fit-time reports for it (the
`initial` x0, v0 of its `tests` entry in the `--json` output), so the
comparison is of the integrator, not of the initialisation. Score = 1000 x
RMSE of y[50:] in volts = RMSE in mV, as fit-time scores.

Usage (numpy and scipy needed):

  nlsdof fit-time ... --test 100:40575 --test 100:32100 --test 105712:127400 \
      --out duffing.toml --json > duffing.json
  python3 scripts/silverbox_independent.py --model duffing.toml --json duffing.json \
      [--csv ../shared/data/silverbox/SNLS80mV.csv]

Prints one line per test set: range, fit-time's score, the DOP853 score and
their relative difference; `--out FILE` also writes them as JSON. A test set
that starts where an earlier one starts, from the same initial state, is the
prefix of that simulation and is not integrated again.
"""
import argparse
import json
import math
import time
import tomllib
from pathlib import Path

import numpy as np
from scipy.integrate import DOP853

FS = 610.3515625  # Hz, Silverbox
INIT_WINDOW = 50
HERE = Path(__file__).resolve().parent


def model_params(path):
    """The model file (mass 1) as per-unit-mass parameters, its input
    reconstruction (cubic when absent) and substeps (for the report)."""
    d = tomllib.loads(Path(path).read_text())
    m = d["mass"]
    sig = d.get("signal", {})
    p = {
        "alpha": d["stiffness"] / m,
        "delta": d["damping"] / m,
        "beta": 0.0, "rho": 2.0, "kappa": 0.0, "eta": 1.0,
        "gain": sig.get("input_gain", 1.0),
        "input_offset": sig.get("input_offset", 0.0),
        "output_offset": sig.get("output_offset", 0.0),
    }
    if "nonlinear_stiffness" in d:
        p["beta"] = d["nonlinear_stiffness"]["coefficient"] / m
        p["rho"] = d["nonlinear_stiffness"]["exponent"]
    if "nonlinear_damping" in d:
        p["kappa"] = d["nonlinear_damping"]["coefficient"] / m
        p["eta"] = d["nonlinear_damping"]["exponent"]
    return p, sig.get("input_interpolation", "cubic"), sig.get("substeps")


def interval_polynomials(u, kind):
    """Coefficients c0..c3 of u(k + s) = c0 + c1 s + c2 s^2 + c3 s^3 on every
    interval k = 0..n-2 (the reconstruction of independent_fit_time.py,
    expanded in s)."""
    n = len(u)
    c = np.zeros((n - 1, 4))
    k = np.arange(n - 1)
    if kind == "zoh":
        c[:, 0] = u[:-1]
        return c
    if kind == "linear" or n < 4:
        c[:, 0] = u[:-1]
        c[:, 1] = u[1:] - u[:-1]
        return c
    if kind != "cubic":
        raise SystemExit(f"unknown input_interpolation {kind!r}")
    b = np.clip(k - 1, 0, n - 4)
    o = (k - b).astype(float)  # x = o + s, o in {0, 1, 2}
    p = np.stack([u[b + j] for j in range(4)], axis=1)
    # Lagrange basis on nodes 0..3 as polynomials in x, then shifted by o.
    basis = [
        np.array([1.0, -11.0 / 6, 1.0, -1.0 / 6]),  # -(x-1)(x-2)(x-3)/6
        np.array([0.0, 3.0, -2.5, 0.5]),  # x(x-2)(x-3)/2
        np.array([0.0, -1.5, 2.0, -0.5]),  # -x(x-1)(x-3)/2
        np.array([0.0, 1.0 / 3, -0.5, 1.0 / 6]),  # x(x-1)(x-2)/6
    ]
    a = sum(np.outer(p[:, j], basis[j]) for j in range(4))  # coeffs in x
    # x = o + s: coefficients in s
    c[:, 0] = a[:, 0] + a[:, 1] * o + a[:, 2] * o**2 + a[:, 3] * o**3
    c[:, 1] = a[:, 1] + 2 * a[:, 2] * o + 3 * a[:, 3] * o**2
    c[:, 2] = a[:, 2] + 3 * a[:, 3] * o
    c[:, 3] = a[:, 3]
    return c


def simulate(p, u, x0, v0, kind, rtol=1e-10, atol=1e-13):
    """x at every sample of u from (x0, v0): DOP853, one solve per interval."""
    coef = interval_polynomials(np.asarray(u, float), kind).tolist()
    alpha, delta, beta, rho = p["alpha"], p["delta"], p["beta"], p["rho"]
    kappa, eta, g, bu = p["kappa"], p["eta"], p["gain"], p["input_offset"]
    h = 1.0 / FS
    xs = np.empty(len(u))
    xs[0] = x0
    state = np.array([x0, v0], float)
    cur = coef[0]
    fabs = math.fabs

    def f(t, z):
        x, v = z
        s = t / h
        c0, c1, c2, c3 = cur
        ui = c0 + s * (c1 + s * (c2 + s * c3))
        a = (g * (ui + bu) - alpha * x - delta * v
             - beta * x * fabs(x) ** rho - kappa * v * fabs(v) ** eta)
        return np.array([v, a])

    first = None
    for k in range(len(u) - 1):
        cur = coef[k]
        solver = DOP853(f, 0.0, state, h, rtol=rtol, atol=atol, first_step=first)
        while solver.status == "running":
            solver.step()
        if solver.status != "finished":
            raise RuntimeError(f"DOP853 failed at interval {k}")
        state = solver.y
        first = min(h, solver.step_size) if solver.step_size else None
        xs[k + 1] = state[0]
    return xs


def read_csv(path):
    d = np.genfromtxt(path, delimiter=",", skip_header=1, usecols=(0, 1))
    return d[:, 0], d[:, 1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", required=True, help="model file written by fit-time --out")
    ap.add_argument("--json", required=True, help="fit-time --json output of the same run")
    ap.add_argument("--csv", default=str(HERE / "../../shared/data/silverbox/SNLS80mV.csv"),
                    help="Silverbox SNLS80mV.csv (columns V1 = u, V2 = y)")
    ap.add_argument("--out", help="write the scores as JSON here")
    a = ap.parse_args()
    u, y = read_csv(a.csv)
    p, kind, substeps = model_params(a.model)
    doc = json.loads(Path(a.json).read_text())
    print(f"{a.model}: input_interpolation {kind}, fit-time substeps {substeps}; "
          f"DOP853 rtol 1e-10, restarted every sample")
    done = {}  # (start, x0, v0) -> (stop, x)
    rows = []
    for t in doc["tests"]:
        lo, hi = t["range"] if "range" in t else (t["start"], t["end"])
        x0, v0 = t["initial"]["x0"], t["initial"]["v0"]
        key = (lo, x0, v0)
        t0 = time.time()
        if key in done and done[key][0] >= hi:
            xm = done[key][1][: hi - lo]
        else:
            xm = simulate(p, u[lo:hi], x0, v0, kind)
            done[key] = (hi, xm)
        dt = time.time() - t0
        ym = xm + p["output_offset"]
        score = 1000 * float(np.sqrt(np.mean((ym[INIT_WINDOW:] - y[lo + INIT_WINDOW:hi]) ** 2)))
        rep = t["score_x1000"]
        rows.append({"range": [lo, hi], "fit_time_mV": rep, "dop853_mV": score,
                     "difference_percent": 100 * (score / rep - 1), "seconds": dt})
        print(f"  [{lo}, {hi}): fit-time {rep:.4f} mV, DOP853 {score:.4f} mV "
              f"({100 * (score / rep - 1):+.3f} %), {dt:.1f} s")
    if a.out:
        Path(a.out).write_text(json.dumps({"model": a.model, "input_interpolation": kind,
                                           "substeps": substeps, "tests": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
