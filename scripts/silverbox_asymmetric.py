#!/usr/bin/env python3
"""Issue 26, item 3: does the Silverbox circuit need an asymmetric term?

An experiment outside the library (numpy, scipy, numba), reported as a
separate row of docs/silverbox.md. It fits, by output error on the official
estimation range, the generalised model of `nlsdof fit-time` with and
without one extra physical term, an even (asymmetric) stiffness q x|x|^0 x,
i.e. q x^2:

    x'' + delta x' + alpha x + kappa v|v|^eta + beta x|x|^rho [+ q x^2]
        = gain (u + input_offset),      y = x + output_offset,

integrated like fit-time (classical RK4, `--substeps` per sample, the
4-point Lagrange cubic input of scripts/silverbox_independent.py), with
scipy's least_squares (trust-region reflective, finite-difference
Jacobian). Each test range is scored as fit-time scores it: x0, v0 fitted to
the first 50 output samples, then the RMS of y[50:] in mV. The first variant
(no extra term) is the check of the script itself: it must reproduce
fit-time's generalised row.

Other variants: the input seen through a one-pole low-pass (an input
filter, pole f_c in Hz) or delayed by a fraction of a sample (either sign).

Usage: python3 scripts/silverbox_asymmetric.py [--substeps 6] [--only TEXT]
(numba is needed: `pip install numba scipy`).
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit
from scipy.optimize import least_squares

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from silverbox_independent import (  # noqa: E402  (the shared input reconstruction)
    FS,
    INIT_WINDOW,
    interval_polynomials,
    read_csv,
)

EST = (40650, 105712)
TESTS = [(100, 40575), (100, 32100), (105712, 127400)]
NAMES = ["alpha", "delta", "beta", "rho", "kappa", "eta", "gain", "input_offset",
         "output_offset", "q", "input_pole_hz", "input_delay_samples"]


@njit(cache=True)
def _accel(th, x, v, ui):
    alpha, delta, beta, rho, kappa, eta, g, bu, q = (th[0], th[1], th[2], th[3], th[4],
                                                      th[5], th[6], th[7], th[9])
    return (g * (ui + bu) - alpha * x - delta * v - beta * x * abs(x) ** rho
            - kappa * v * abs(v) ** eta - q * x * x)


@njit(cache=True)
def _filt(th, w, ui):
    """dw/dt of the input filter state (th[10] its pole in Hz; 0: no filter)."""
    return 2.0 * np.pi * th[10] * (ui - w)


@njit(cache=True)
def _u_at(coef, t):
    """The cubic input reconstruction at time t (in samples, clamped)."""
    n = coef.shape[0]
    if t <= 0.0:
        k, s = 0, 0.0
    elif t >= n:
        k, s = n - 1, 1.0
    else:
        k = int(t)
        s = t - k
    return coef[k, 0] + s * (coef[k, 1] + s * (coef[k, 2] + s * coef[k, 3]))


@njit(cache=True)
def rk4(th, coef, x0, v0, substeps, h):
    """x at every sample; with th[10] > 0 the model sees the input through a
    one-pole low-pass w' = 2 pi f_c (u - w), w(0) = u(0)."""
    n = coef.shape[0] + 1
    xs = np.empty(n)
    xs[0] = x0
    x, v = x0, v0
    w = coef[0, 0]
    filt = th[10] > 0.0
    dt = h / substeps
    for k in range(n - 1):
        c0, c1, c2, c3 = coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3]
        for j in range(substeps):
            s0 = j / substeps
            s1 = (j + 0.5) / substeps
            s2 = (j + 1.0) / substeps
            if th[11] != 0.0:  # input delayed by th[11] samples (negative: a lead)
                u0 = _u_at(coef, k + s0 - th[11])
                u1 = _u_at(coef, k + s1 - th[11])
                u2 = _u_at(coef, k + s2 - th[11])
            else:
                u0 = c0 + s0 * (c1 + s0 * (c2 + s0 * c3))
                u1 = c0 + s1 * (c1 + s1 * (c2 + s1 * c3))
                u2 = c0 + s2 * (c1 + s2 * (c2 + s2 * c3))
            if filt:
                k1w = _filt(th, w, u0)
                w2 = w + 0.5 * dt * k1w
                k2w = _filt(th, w2, u1)
                w3 = w + 0.5 * dt * k2w
                k3w = _filt(th, w3, u1)
                w4 = w + dt * k3w
                k4w = _filt(th, w4, u2)
                e0, e1, e2, e3 = w, w2, w3, w4
            else:
                e0, e1, e2, e3 = u0, u1, u1, u2
                k1w = k2w = k3w = k4w = 0.0
            k1x, k1v = v, _accel(th, x, v, e0)
            k2x, k2v = v + 0.5 * dt * k1v, _accel(th, x + 0.5 * dt * k1x, v + 0.5 * dt * k1v, e1)
            k3x, k3v = v + 0.5 * dt * k2v, _accel(th, x + 0.5 * dt * k2x, v + 0.5 * dt * k2v, e2)
            k4x, k4v = v + dt * k3v, _accel(th, x + dt * k3x, v + dt * k3v, e3)
            x += dt / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x)
            v += dt / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)
            w += dt / 6.0 * (k1w + 2 * k2w + 2 * k3w + k4w)
            if not np.isfinite(x):
                xs[k + 1:] = np.inf
                return xs
        xs[k + 1] = x
    return xs


def fit(u, y, th0, free, substeps, x0v0):
    """Output-error fit over `free` (indices into θ) and x0, v0."""
    coef = interval_polynomials(u, "cubic")
    h = 1.0 / FS
    scale = np.where(th0 != 0, np.abs(th0), 1.0)

    def unpack(z):
        th = th0.copy()
        th[free] = z[:-2] * scale[free]
        return th, z[-2] * 1e-3, z[-1] * 1e-1

    def res(z):
        th, x0, v0 = unpack(z)
        r = rk4(th, coef, x0, v0, substeps, h) + th[8] - y
        return np.where(np.isfinite(r), r, 1e3)

    z0 = np.concatenate([th0[free] / scale[free], [x0v0[0] * 1e3, x0v0[1] * 1e1]])
    lo = np.full(len(z0), -np.inf)
    for i, p in enumerate(free):
        if NAMES[p] in ("delta", "kappa", "eta", "rho", "input_pole_hz"):
            lo[i] = 0.0
    z0 = np.maximum(z0, lo)
    r = least_squares(res, z0, bounds=(lo, np.inf), method="trf", x_scale="jac",
                      ftol=1e-12, xtol=1e-12, gtol=1e-12, max_nfev=400)
    th, x0, v0 = unpack(r.x)
    return th, (x0, v0), float(np.sqrt(np.mean(r.fun ** 2))), r


def score(u_all, y_all, th, substeps):
    """fit-time's score of each test range (mV) and the initial states."""
    out = []
    h = 1.0 / FS
    for lo, hi in TESTS:
        u, y = u_all[lo:hi], y_all[lo:hi]
        coef_init = interval_polynomials(u[:INIT_WINDOW], "cubic")
        yi = y[:INIT_WINDOW]

        def r0(z):
            return rk4(th, coef_init, z[0] * 1e-3, z[1] * 1e-1, substeps, h) + th[8] - yi
        x0 = yi[0] - th[8]
        v0 = (-3 * yi[0] + 4 * yi[1] - yi[2]) / (2 / FS)
        s = least_squares(r0, [x0 * 1e3, v0 * 1e1], xtol=1e-14, ftol=1e-14, gtol=1e-14)
        x0, v0 = s.x[0] * 1e-3, s.x[1] * 1e-1
        xm = rk4(th, interval_polynomials(u, "cubic"), x0, v0, substeps, h)
        rms = np.sqrt(np.mean((xm[INIT_WINDOW:] + th[8] - y[INIT_WINDOW:]) ** 2))
        out.append((1000 * rms, x0, v0))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--csv", default=str(HERE / "../../shared/data/silverbox/SNLS80mV.csv"))
    ap.add_argument("--substeps", type=int, default=6)
    ap.add_argument("--only", help="run only the variants whose label contains this text")
    a = ap.parse_args()
    u_all, y_all = read_csv(a.csv)
    u, y = u_all[EST[0]:EST[1]], y_all[EST[0]:EST[1]]
    # start: fit-time's converged generalised fit (docs/silverbox.md)
    th0 = np.array([184168.0, 1e-3, 713310.0, 1.98198, 39.5433, 0.0165581, 186814.0,
                    -0.00829691, 0.00289967, 0.0, 0.0, 0.0])
    x0v0 = (y[0] - th0[8], 0.0)
    variants = [("generalised (9)", list(range(9)), 0.0),
                ("generalised + input delay (10)", list(range(9)) + [11], 0.0),
                ("generalised + q x^2 (10)", list(range(10)), 0.0),
                ("generalised, delta = 0, + q x^2 (9)", [0, 2, 3, 4, 5, 6, 7, 8, 9], 0.0),
                ("generalised + input pole (10)", list(range(9)) + [10], 300.0),
                ("generalised, delta = 0, + input pole (9)", [0, 2, 3, 4, 5, 6, 7, 8, 10],
                 300.0)]
    only = [v for v in variants if a.only is None or a.only in v[0]]
    for label, free, pole in only:
        th_start = th0.copy()
        th_start[10] = pole
        if 11 in free:
            th_start[11] = 0.05
        if 1 not in free:
            th_start[1] = 0.0
        t0 = time.time()
        th, init, est, r = fit(u, y, th_start, free, a.substeps, x0v0)
        dt = time.time() - t0
        sc = score(u_all, y_all, th, a.substeps)
        print(f"{label}: estimation RMS {1000 * est:.4f} mV, tests "
              + " / ".join(f"{s[0]:.4f}" for s in sc) + f" mV; {r.nfev} evaluations, "
              f"{dt:.0f} s, status {r.status}")
        print("   " + ", ".join(f"{n} = {v:.6g}" for n, v in zip(NAMES, th)))


if __name__ == "__main__":
    main()
