"""Every matplotlib figure of nlsdof (``pip install nlsdof[plot]``), each the
Python twin of a CLI ``--plot`` figure, on data the library makes itself (a
Duffing oscillator, f_n = 10 Hz): no files needed.

    python plots.py [--out DIR]

1. ``FitResult.plot``: stepped-sine data and the fitted model, one colour
   per level, up-sweeps solid with filled dots, down-sweeps dashed with
   hollow circles (``nlsdof fit --plot``);
2. ``FitResult.plot_landscape``: the exponent landscape (``--landscape``);
3. ``nlsdof.plot.decay``: record with its envelopes, backbone, damping curve
   (``nlsdof decay --plot``);
4. ``nlsdof.plot.fit_time``: measured and model output of a time fit;
5. ``nlsdof.plot.linear_id``: |H|, phase and Nyquist (``nlsdof linear-id
   --plot``);
6. ``Spectrogram.plot``: the STFT heat map (``nlsdof spectrogram --plot``);
7. ``.plot()`` on the documents themselves: ``decay``, ``fit_time`` and
   ``linear_id`` return a ``Report`` (a dict with ``plot()``), so
   ``nlsdof.decay(x, fs).plot(x)`` draws 3.'s first panel.

SI units; amplitudes zero-to-peak, drawn in one length unit chosen from the
data and stated on each axis.
"""

import argparse
import pathlib
from typing import Any

import numpy as np

import nlsdof
import nlsdof.plot


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="plots-python", help="output folder")
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    wn = 2 * np.pi * 10.0
    duffing = nlsdof.Model(1.0, wn**2, 0.02 * wn, nonlinear_stiffness=(2.5e6, 2.0))

    # 1. stepped-sine data (3 levels up, the highest also down) and the fit
    f = np.linspace(8.5, 12.0, 40)
    cols: dict[str, list[Any]] = {"level": [], "gamma": [], "f_hz": [], "amplitude": [], "sweep": []}
    for i, gamma in enumerate((0.1, 0.2, 0.3)):
        for direction in ("up", "down") if i == 2 else ("up",):
            s = duffing.sweep(gamma, f, direction)
            cols["level"] += [f"{gamma} m/s2"] * len(f)
            cols["gamma"] += [gamma] * len(f)
            cols["f_hz"] += list(f)
            cols["amplitude"] += list(s.amplitude)
            cols["sweep"] += [direction] * len(f)
    r = nlsdof.fit(cols, "generalised-stiffness", grid=[16, 1])
    ax = r.plot()
    ax.figure.savefig(out / "fit.png", dpi=100)
    ax = r.plot_landscape()
    ax.figure.savefig(out / "landscape.png", dpi=100)

    # 3. free decay from 1 mm, sampled at 1 kHz
    fs = 1000.0
    sim = duffing.simulate(np.zeros(20_000), fs=fs, x0=1e-3)
    x = np.asarray(sim[0])
    d = nlsdof.decay(x, fs, t_start=0.0)
    fig, axes = plt.subplots(3, 1, figsize=(10, 11))
    for a, what in zip(axes, ("envelope", "backbone", "damping")):
        nlsdof.plot.decay(d, x, ax=a, what=what, column="x", unit="m")
    fig.savefig(out / "decay.png", dpi=100)

    # 4. time fit: a noisy chirp through the model, fitted on the first
    # half and tested on the second
    t = np.arange(8000) / fs
    u = 2.0 * np.sin(2 * np.pi * (6.0 + 1.0 * t) * t)
    y = np.asarray(duffing.simulate(u, fs=fs)[0])
    y = y + 1e-3 * np.abs(y).max() * np.random.default_rng(1).standard_normal(len(y))
    tf = nlsdof.fit_time(u, y, fs, model="duffing", fit_range=[0, 4000], tests=[[4000, 8000]])
    ax = nlsdof.plot.fit_time(tf, y)
    ax.figure.savefig(out / "fit_time.png", dpi=100)

    # 5. linear identification of the linear part's receptance
    ff = np.linspace(7.0, 13.0, 300)
    jw = 2j * np.pi * ff
    h = 1.0 / (jw**2 + 0.02 * wn * jw + wn**2)
    lin = nlsdof.linear_id(ff, h, input="acceleration", output="displacement")
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.5))
    for a, what in zip(axes, ("magnitude", "phase", "nyquist")):
        nlsdof.plot.linear_id(lin, ax=a, what=what)
    fig.savefig(out / "linear_id.png", dpi=100)

    # 6. spectrogram of the chirp's response
    ax = nlsdof.spectrogram(y, fs).plot()
    ax.figure.savefig(out / "spectrogram.png", dpi=100)

    # 7. the results draw themselves (typed: the stubs return Report)
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.5))
    d.plot(x, ax=axes[0], column="x", unit="m")
    tf.plot(y, ax=axes[1])
    lin.plot(ax=axes[2], what="nyquist")
    fig.savefig(out / "report_plots.png", dpi=100)
    print(f"figures written to {out}/")


if __name__ == "__main__":
    main()
