#!/usr/bin/env python3
"""Reference results for the Rust fast relaxed vector fitting (FRVF).

A straightforward numpy implementation of the same algorithm as
crates/nlsdof/src/vector_fitting/frvf.rs, written independently and kept
deliberately plain (dense matrices, numpy.linalg.qr / lstsq / eigvals):

* frequency normalisation s = j w / w_max;
* starting poles -0.01 b +/- j b, b linearly spaced over [w_min, w_max]/w_max
  (Gustavsen & Semlyen 1999);
* relaxed pole relocation: least squares for
      sum c_n phi_n + d + s e - H (sum ct_n phi_n + dt) = 0
  (real basis phi' = 1/(s-a) + 1/(s-conj a), phi'' = j/(s-a) - j/(s-conj a)),
  real and imaginary parts stacked, each row times the weight; the R22 block
  of the QR factor of [A1 A2] plus the relaxation row
  scale * (Re sum_k sigma(s_k) = Ns), scale = ||w H|| / Ns
  (Gustavsen 2006; fast form of Deschrijver et al. 2008); |dt| < 1e-8 -> dt
  fixed to +/-1e-8;
* new poles = eig(A - b ct^T / dt), unstable ones flipped;
* residues, d, e by weighted linear least squares; RMS error unweighted.

The data are generated here with numpy's default_rng (seeded) and written
with the results, so the Rust test (crates/nlsdof/tests/vector_fitting.rs)
only reads the output file; CI does not run Python.

Usage:  python3 scripts/vf_reference.py > crates/nlsdof/tests/data/vf_reference.txt
"""

import numpy as np

ITERATIONS = 8


def basis(s, poles):
    cols = []
    for a in poles:
        if a.imag > 0:
            p = 1.0 / (s - a)
            q = 1.0 / (s - np.conj(a))
            cols.append(p + q)
            cols.append(1j * (p - q))
        else:
            cols.append(1.0 / (s - a))
    return np.array(cols).T  # Ns x N


def realify(m):
    return np.vstack([m.real, m.imag])


def lstsq(a, b):
    return np.linalg.lstsq(a, b, rcond=None)[0]


def relocate(s, f, w, poles, constant, proportional):
    ns = len(s)
    phi = basis(s, poles)
    n = phi.shape[1]
    a1 = [phi * w[:, None]]
    if constant:
        a1.append(w[:, None] * np.ones((ns, 1)))
    if proportional:
        a1.append((w * s)[:, None])
    a1 = np.hstack(a1)
    a2 = np.hstack([-(w * f)[:, None] * phi, -(w * f)[:, None]])
    a = realify(np.hstack([a1, a2]))
    n1 = a1.shape[1]
    r = np.linalg.qr(a, mode="r")
    r22 = r[n1:, n1:]
    scale = np.linalg.norm(w * f) / ns
    row = np.concatenate([phi.real.sum(axis=0), [ns]]) * scale
    m = np.vstack([r22, row])
    rhs = np.zeros(n + 2)
    rhs[-1] = ns * scale
    x = lstsq(m, rhs)
    ct, dt = x[:n], x[n]
    if abs(dt) < 1e-8:
        dt = -1e-8 if dt < 0 else 1e-8
        ct = lstsq(r22[:, :n], -r22[:, n] * dt)
    amat = np.zeros((n, n))
    bvec = np.zeros(n)
    col = 0
    for p in poles:
        if p.imag > 0:
            amat[col:col + 2, col:col + 2] = [[p.real, p.imag], [-p.imag, p.real]]
            bvec[col] = 2.0
            col += 2
        else:
            amat[col, col] = p.real
            bvec[col] = 1.0
            col += 1
    eig = np.linalg.eigvals(amat - np.outer(bvec, ct) / dt)
    new = [complex(-abs(e.real) if e.real > 0 else e.real, e.imag) for e in eig if e.imag >= 0]
    new.sort(key=lambda z: (z.imag, z.real))
    return new


def residues(s, f, w, poles, constant, proportional):
    ns = len(s)
    phi = basis(s, poles)
    n = phi.shape[1]
    cols = [phi]
    if constant:
        cols.append(np.ones((ns, 1)))
    if proportional:
        cols.append(s[:, None])
    a = np.hstack(cols)
    x = lstsq(realify(a * w[:, None]), np.concatenate([(w * f).real, (w * f).imag]))
    fit = a @ x
    rms = np.sqrt(np.mean(np.abs(f - fit) ** 2))
    res = []
    j = 0
    for p in poles:
        if p.imag > 0:
            res.append(complex(x[j], x[j + 1]))
            j += 2
        else:
            res.append(complex(x[j], 0.0))
            j += 1
    d = x[n] if constant else 0.0
    e = x[-1] if proportional else 0.0
    return res, d, e, rms


def vf(omega, h, pairs, constant, proportional, weights):
    w0 = omega[-1]
    s = 1j * omega / w0
    w = np.ones(len(s)) if weights is None else weights
    wmin = omega[0] / w0
    betas = [0.5 * (wmin + 1.0)] if pairs == 1 else [wmin + (1.0 - wmin) * i / (pairs - 1) for i in range(pairs)]
    poles = [complex(-0.01 * b, b) for b in betas]
    history = []
    for _ in range(ITERATIONS):
        poles = relocate(s, h, w, poles, constant, proportional)
        res, d, e, rms = residues(s, h, w, poles, constant, proportional)
        history.append(rms)
    return [p * w0 for p in poles], [r * w0 for r in res], d, e / w0, history


def synthetic(n, f0, f1, modes, noise, seed):
    omega = 2 * np.pi * np.linspace(f0, f1, n)
    h = np.zeros(n, dtype=complex)
    for fn, z, a in modes:
        wn = 2 * np.pi * fn
        h += a / (wn ** 2 - omega ** 2 + 2j * z * wn * omega)
    rng = np.random.default_rng(seed)
    href = np.sqrt(np.mean(np.abs(h) ** 2))
    h = h + noise * href / np.sqrt(2) * (rng.standard_normal(n) + 1j * rng.standard_normal(n))
    return omega, h


def fmt(xs):
    return " ".join(repr(float(x)) for x in xs)


def main():
    modes = [(20.0, 0.01, 1.0), (47.0, 0.02, -2.5), (83.0, 0.015, 4.0)]
    cases = [
        ("three_modes_noise_uniform", 3, True, False, False, 0.01),
        ("three_modes_noise_inverse_weight_proportional", 3, True, True, True, 0.01),
    ]
    print("# Reference FRVF results from scripts/vf_reference.py (numpy %s); do not edit by hand." % np.__version__)
    print("# One block per case: options, data (omega rad/s, H re/im, weights), and the results")
    print("# after %d iterations: poles (Im >= 0), residues, d, e, RMS error per iteration." % ITERATIONS)
    for k, (name, pairs, constant, proportional, inverse, noise) in enumerate(cases):
        omega, h = synthetic(500, 10.0, 100.0, modes, noise, 1234 + k)
        weights = 1.0 / np.abs(h) if inverse else None
        poles, res, d, e, hist = vf(omega, h, pairs, constant, proportional, weights)
        print("case", name)
        print("options", pairs, int(constant), int(proportional), ITERATIONS)
        print("omega", fmt(omega))
        print("h_re", fmt(h.real))
        print("h_im", fmt(h.imag))
        print("weights", fmt(weights if weights is not None else np.ones(len(h))))
        print("pole_re", fmt([p.real for p in poles]))
        print("pole_im", fmt([p.imag for p in poles]))
        print("residue_re", fmt([r.real for r in res]))
        print("residue_im", fmt([r.imag for r in res]))
        print("d", repr(float(d)))
        print("e", repr(float(e)))
        print("rms", fmt(hist))
        print("end")


if __name__ == "__main__":
    main()
