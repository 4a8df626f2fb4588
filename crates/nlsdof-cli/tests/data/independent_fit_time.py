#!/usr/bin/env python3
"""Independent check of `nlsdof fit-time` (issue 26): the fitted model file,
integrated by an accurate integrator that shares no code with nlsdof
(scipy `solve_ivp`, DOP853, rtol 1e-10, restarted at every sample so the
kinks of the input reconstruction are step boundaries), reproduces the
test score that fit-time reports; and on a synthetic Duffing record whose
truth is known, the fitted parameters match the truth to the noise, not to
the integration step.

Writes, beside this script:
  independent_duffing.csv   the record (columns u, y): a random-phase
                            multisine through the true Duffing oscillator,
                            integrated by DOP853 with the cubic input
                            reconstruction, plus seeded white noise on y
  independent_fit_time.json the truth, the fit-time runs (arguments, fitted
                            parameters, reported scores) and the scores of
                            their model files by DOP853 with the model
                            file's stated input reconstruction

Usage (from the repository root; needs numpy, scipy and a release build):
  python crates/nlsdof-cli/tests/data/independent_fit_time.py \
      --nlsdof target/release/nlsdof
The Rust test crates/nlsdof-cli/tests/fit_time_independent.rs reruns the
same fit-time commands and compares.
"""
import argparse
import json
import subprocess
import tempfile
import tomllib
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

HERE = Path(__file__).resolve().parent
RECORD = HERE / "independent_duffing.csv"
REFERENCE = HERE / "independent_fit_time.json"

FS = 1000.0  # Hz
N = 3000  # samples
F_N = 62.5  # Hz: 16 samples per cycle of the linear resonance
OMEGA = 2 * np.pi * F_N
# x'' + delta x' + alpha x + beta x^3 = gain (u + input_offset), y = x + output_offset
TRUTH = {
    "alpha": OMEGA**2,
    "delta": 2 * 0.02 * OMEGA,
    "beta": 0.4 * OMEGA**2,
    "gain": OMEGA**2,
    "input_offset": 0.02,
    "output_offset": 0.01,
}
NOISE = 1e-4  # noise RMS relative to the RMS of x
ESTIMATION = (0, 2000)
TEST = (2000, 3000)
INIT_WINDOW = 50


def multisine(n):
    """Random-phase multisine, 2..100 Hz every 2 Hz, RMS 0.1 (seeded)."""
    rng = np.random.default_rng(7)
    f = np.arange(2.0, 101.0, 2.0)
    ph = rng.uniform(0, 2 * np.pi, f.size)
    t = np.arange(n) / FS
    u = np.sin(2 * np.pi * f[None, :] * t[:, None] + ph[None, :]).sum(axis=1)
    return 0.1 * u / np.sqrt(np.mean(u**2))


def reconstruction(u, kind):
    """u(k + s), s in [0, 1], on interval k, as nlsdof states it: cubic =
    the 4-point Lagrange cubic through samples b..b+3, b = clamp(k-1, 0,
    n-4); linear; zoh = u[k] on [k, k+1)."""
    n = len(u)

    def at(k, s):
        if kind == "zoh":
            return u[k]
        if kind == "linear" or n < 4:
            return u[k] + s * (u[k + 1] - u[k])
        b = min(max(k - 1, 0), n - 4)
        x = k - b + s
        p = u[b : b + 4]
        l0 = -(x - 1) * (x - 2) * (x - 3) / 6
        l1 = x * (x - 2) * (x - 3) / 2
        l2 = -x * (x - 1) * (x - 3) / 2
        l3 = x * (x - 1) * (x - 2) / 6
        return l0 * p[0] + l1 * p[1] + l2 * p[2] + l3 * p[3]

    return at


def simulate(p, u, x0, v0, kind):
    """x at every sample: DOP853, rtol 1e-10, one solve per sample interval."""
    at = reconstruction(u, kind)
    rho = p.get("rho", 2.0)
    eta = p.get("eta", 1.0)
    alpha, delta, beta = p["alpha"], p["delta"], p.get("beta", 0.0)
    kappa, g, bu = p.get("kappa", 0.0), p["gain"], p["input_offset"]
    h = 1.0 / FS
    xs = np.empty(len(u))
    s = np.array([x0, v0])
    xs[0] = x0
    for k in range(len(u) - 1):

        def f(t, z, k=k):
            x, v = z
            a = (g * (at(k, t / h) + bu) - alpha * x - delta * v
                 - beta * x * abs(x) ** rho - kappa * v * abs(v) ** eta)
            return [v, a]

        r = solve_ivp(f, (0.0, h), s, method="DOP853", rtol=1e-10, atol=1e-13)
        s = r.y[:, -1]
        xs[k + 1] = s[0]
    return xs


def model_params(path):
    """The model file (mass 1) as the parameters of `simulate`, and its
    stated input reconstruction (cubic when absent)."""
    d = tomllib.loads(Path(path).read_text())
    m = d["mass"]
    sig = d.get("signal", {})
    p = {
        "alpha": d["stiffness"] / m,
        "delta": d["damping"] / m,
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
    return p, sig.get("input_interpolation", "cubic")


def fit_args(extra):
    return [
        "fit-time", "--input", str(RECORD), "--input-column", "u", "--output-column", "y",
        "--fs", repr(FS), "--range", f"{ESTIMATION[0]}:{ESTIMATION[1]}",
        "--test", f"{TEST[0]}:{TEST[1]}", "--model", "duffing", "--json",
    ] + extra


RUNS = {
    "cubic_auto": [],
    "cubic_fixed_h_half": ["--substeps", "2"],
    "linear_auto": ["--input-interpolation", "linear"],
    "zoh_auto": ["--input-interpolation", "zoh"],
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--nlsdof", required=True, help="path of the nlsdof binary")
    a = ap.parse_args()
    u = multisine(N)
    x = simulate(TRUTH, u, 0.0, 0.0, "cubic")
    rng = np.random.default_rng(11)
    y = x + TRUTH["output_offset"] + NOISE * np.sqrt(np.mean(x**2)) * rng.standard_normal(N)
    with open(RECORD, "w") as fh:
        fh.write("u,y\n")
        for a_, b_ in zip(u, y):
            fh.write(f"{a_:.15e},{b_:.15e}\n")
    ref = {
        "fs": FS, "samples": N, "estimation": ESTIMATION, "test": TEST,
        "truth": TRUTH, "noise_relative": NOISE, "runs": {},
    }
    with tempfile.TemporaryDirectory() as tmp:
        for name, extra in RUNS.items():
            model = Path(tmp) / f"{name}.toml"
            out = subprocess.run(
                [a.nlsdof] + fit_args(extra + ["--out", str(model)]),
                check=True, capture_output=True, text=True,
            ).stdout
            doc = json.loads(out)
            test = doc["tests"][0]
            p, kind = model_params(model)
            lo, hi = TEST
            xm = simulate(p, u[lo:hi], test["initial"]["x0"], test["initial"]["v0"], kind)
            ym = xm + p["output_offset"]
            score = float(np.sqrt(np.mean((ym[INIT_WINDOW:] - y[lo + INIT_WINDOW:hi]) ** 2)))
            ref["runs"][name] = {
                "args": extra,
                "input_interpolation": kind,
                "substeps": doc["integration"]["substeps"],
                "parameters": doc["parameters"],
                "std_errors": {i["name"]: i["std_error"] for i in doc["intervals_95"]},
                "reported_test_rms": test["rms"],
                "independent_test_rms": score,
                "initial": test["initial"],
            }
            print(f"{name}: substeps {doc['integration']['substeps']}, reported {test['rms']:.6e}, "
                  f"DOP853 {score:.6e} ({100 * (score / test['rms'] - 1):+.3f} %)")
            for k in ("alpha", "delta", "beta", "gain"):
                v, se = doc["parameters"][k], ref["runs"][name]["std_errors"][k]
                print(f"   {k}: {v:.8g} vs {TRUTH[k]:.8g}: {(v - TRUTH[k]) / se:+.2f} sigma")
    REFERENCE.write_text(json.dumps(ref, indent=1) + "\n")


if __name__ == "__main__":
    main()
