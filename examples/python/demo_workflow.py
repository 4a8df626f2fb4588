"""The paper's workflow from Python, on the virtual HAR wing (what
`nlsdof demo` does in Rust), with matplotlib figures.

1. test: the virtual stepped-sine rig at the five levels of Table 2 over
   5.3-5.5 Hz (time simulation until steady at each step), plus 1 % noise;
2. linear identification: a low-level chirp, its FRF (H1 by FFT ratio),
   vector fitting (nlsdof.linear_id) -> alpha = k/m, delta = c/m;
3. fit: the generalised power-law model (Eq 31) with the linear part held;
4. time domain: true and fitted model driven by one stepped-sine record,
   compared by spectrograms (Eq 33).

    python demo_workflow.py [--quick] [--out DIR]

SI units; levels and amplitudes zero-to-peak.
"""

import argparse
import json
import pathlib
import time

import numpy as np

import nlsdof

MASS, K, C = 0.26699, 306.7878, 0.1164
K_R, RHO, C_E, ETA = 85000.0, 4.0022, 0.01591, 3.03099
LEVELS_PP = (0.82, 1.24, 1.62, 2.00, 2.46)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer steps and a shorter chirp (seconds)")
    ap.add_argument("--out", default="demo-python", help="output folder")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    clock = {}

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    wing = nlsdof.Model(mass=MASS, stiffness=K, damping=C,
                        nonlinear_stiffness=(K_R, RHO), nonlinear_damping=(C_E, ETA))
    print(wing, f"f_n = {wing.f_n_hz:.4f} Hz, zeta = {wing.zeta:.3e}")

    # 1. the virtual rig
    t0 = time.perf_counter()
    steps = 21 if args.quick else 61
    f = np.linspace(5.3, 5.5, steps)
    cols = {"level": [], "gamma": [], "f_hz": [], "amplitude": [], "sweep": []}
    for i, pp in enumerate(LEVELS_PP):
        gamma = pp / 2.0
        rig = wing.stepped_sine(gamma=gamma, f_hz=f, samples_per_cycle=32 if args.quick else 64)
        a = rig.amplitude * (1.0 + 0.01 * rng.standard_normal(steps))
        cols["level"] += [str(i + 1)] * steps
        cols["gamma"] += [gamma] * steps
        cols["f_hz"] += list(rig.f_hz)
        cols["amplitude"] += list(a)
        cols["sweep"] += ["up"] * steps
    clock["rig"] = time.perf_counter() - t0

    # 2. linear identification from a low-level chirp
    t0 = time.perf_counter()
    fs = 64.0
    f0, f1 = 4.5, 6.0
    rate = 0.02 if args.quick else 0.005  # Hz/s
    duration = (f1 - f0) / rate + 40.0
    t = np.arange(int(duration * fs)) / fs
    phase = 2 * np.pi * (f0 * t + 0.5 * rate * t**2)
    u = 0.25 * np.sin(phase) * (t < (f1 - f0) / rate)
    x, _ = wing.simulate(u, fs=fs)
    U, X = np.fft.rfft(u), np.fft.rfft(x)
    fr = np.fft.rfftfreq(len(u), 1.0 / fs)
    band = (fr > 4.9) & (fr < 5.9)
    lin = nlsdof.linear_id(fr[band], X[band] / U[band], input="acceleration",
                           output="displacement", poles=1)
    alpha, delta = lin["sdof"]["alpha"], lin["sdof"]["delta"]
    clock["linear"] = time.perf_counter() - t0
    print(f"linear part: alpha = {alpha:.6g} 1/s^2 (true {K / MASS:.6g}), "
          f"delta = {delta:.4g} 1/s (true {C / MASS:.4g})")

    # 3. the fit (Eq 31), linear part held
    t0 = time.perf_counter()
    res = nlsdof.fit(cols, model="generalised", mass=MASS, fix={"alpha": alpha, "delta": delta})
    clock["fit"] = time.perf_counter() - t0
    print(res)
    for name, p in res.parameters.items():
        print(f"  {name:<6} {p['value']:.6g} {p['unit']:<16} physical {p['physical']['name']} = "
              f"{p['physical']['value']:.6g} {p['physical']['unit']}")
    fitted = res.model

    # 4. time domain: one stepped-sine record at the top level
    t0 = time.perf_counter()
    gamma = LEVELS_PP[-1] / 2.0
    dwell = 20.0 if args.quick else 60.0
    pieces = [gamma * np.sin(2 * np.pi * fk * np.arange(int(dwell * fs)) / fs)
              for fk in np.linspace(5.3, 5.5, 5)]
    u2 = np.concatenate(pieces)
    x_true, _ = wing.simulate(u2, fs=fs)
    x_fit, _ = fitted.simulate(u2, fs=fs)
    measured = x_true * (1.0 + 0.01 * rng.standard_normal(len(x_true)))
    eq33 = nlsdof.compare_spectrograms(measured, x_fit, fs=fs, f_min=4.0, f_max=7.0)
    s_meas = nlsdof.spectrogram(measured, fs=fs, f_min=4.0, f_max=7.0)
    clock["time"] = time.perf_counter() - t0
    print(f"Eq 33: max {eq33['eq33_max_relative_percent']:.3g} %, robust "
          f"{eq33['robust_max_relative_percent']:.3g} %, global {eq33['global_relative_percent']:.3g} %")

    # figures
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.4))
    levels = sorted(set(cols["level"]))
    fa = np.array(cols["f_hz"])
    aa = np.array(cols["amplitude"])
    la = np.array(cols["level"])
    fine = np.linspace(5.3, 5.5, 400)
    for i, lv in enumerate(levels):
        sel = la == lv
        g = cols["gamma"][list(la).index(lv)]
        axes[0].plot(fa[sel], 1e3 * aa[sel], "o", ms=3, color=f"C{i}", label=f"gamma = {g:.2f} m/s^2")
        axes[0].plot(fine, 1e3 * fitted.sweep(gamma=g, f_hz=fine).amplitude, "-", color=f"C{i}")
    axes[0].set(xlabel="frequency [Hz]", ylabel="amplitude [mm]",
                title="Rig data (dots) and fitted generalised model (lines)")
    axes[0].legend(fontsize=8)
    axes[1].semilogy(fr[band], np.abs(X[band] / U[band]), ".", ms=3, label="chirp H1")
    h_fit = 1.0 / (alpha - (2 * np.pi * fr[band]) ** 2 + 1j * delta * 2 * np.pi * fr[band])
    axes[1].semilogy(fr[band], np.abs(h_fit), "-", label="identified linear part")
    axes[1].set(xlabel="frequency [Hz]", ylabel="|X/U| [s^2]", title="Linear identification")
    axes[1].legend(fontsize=8)
    im = axes[2].pcolormesh(s_meas.times, s_meas.frequencies, 20 * np.log10(s_meas.magnitude.T + 1e-30),
                            shading="auto")
    axes[2].set(xlabel="time [s]", ylabel="frequency [Hz]",
                title=f"Spectrogram of x (Eq 33 robust max {eq33['robust_max_relative_percent']:.2g} %)")
    fig.colorbar(im, ax=axes[2], label="dB re 1 m")
    fig.tight_layout()
    fig.savefig(out / "workflow.png", dpi=100)

    summary = {
        "linear": lin["sdof"],
        "fit": res.to_dict(),
        "eq33": eq33,
        "timings_s": clock,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    (out / "fitted.toml").write_text(res.to_toml())
    print(f"wrote {out / 'workflow.png'}, {out / 'summary.json'}, {out / 'fitted.toml'}; "
          + ", ".join(f"{k} {v:.2f} s" for k, v in clock.items()))


if __name__ == "__main__":
    main()
