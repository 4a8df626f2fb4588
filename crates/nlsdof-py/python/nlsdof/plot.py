"""matplotlib figures of nlsdof results (an optional extra:
``pip install nlsdof[plot]``). Each function takes ``ax=None`` (a new figure
when None) and returns the Axes, as pandas and seaborn plotting do, and draws
what the CLI's ``--plot`` figure of the same result shows, with the same
conventions:

* ``COLOURS``: one colour per level, 20 distinct (the CLI's palette);
* up-sweeps solid lines and filled dots, down-sweeps dashed lines and hollow
  circles (``sweep_style``);
* one length unit per figure, chosen from the data's magnitude and stated on
  the axis (``length_unit``: m, mm, µm or nm);
* legends outside the axes.

The results' own ``plot`` methods call these: ``FitResult.plot`` (``fit``),
``FitResult.plot_landscape`` (``landscape``), ``Spectrogram.plot``
(``spectrogram``) and the ``plot`` of the documents of ``decay``,
``fit_time`` and ``linear_id`` (``decay``, ``fit_time``, ``linear_id``).
"""

from __future__ import annotations

import math
from typing import Any

# The CLI's palette (nlsdof-figure COLOURS): Tableau-10 without its grey, then
# eleven colours chosen for the largest CIELAB distance to those before.
COLOURS = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2",
    "#bcbd22", "#17becf", "#0000ff", "#ff22ff", "#003300", "#001199", "#332244",
    "#ff0077", "#886600", "#77bb88", "#880044", "#0077ff", "#ff8888",
]
GREY = "#969696"
DARK = "#282828"
# the CLI's dash of down-sweeps: 7 px on, 4 px off (in units of the line width 2)
_DOWN_DASH = (0, (3.5, 2.0))


def colour(i: int) -> str:
    """The `i`-th colour of the palette (cycling after 20)."""
    return COLOURS[i % len(COLOURS)]


def sweep_style(sweep: str) -> dict[str, Any]:
    """matplotlib keywords of a sweep direction: ``linestyle`` of the model
    line and ``marker``/``fillstyle`` of the measured points."""
    if str(sweep).lower().startswith("d"):
        return {"linestyle": _DOWN_DASH, "marker": "o", "fillstyle": "none"}
    return {"linestyle": "-", "marker": "o", "fillstyle": "full"}


def length_unit(peak: float) -> tuple[str, float]:
    """One length unit for a figure: the largest of m, mm, µm and nm in which
    `peak` (metres) is at least 1, and its scale factor from metres."""
    peak = abs(float(peak)) if math.isfinite(float(peak)) else 0.0
    for name, scale in (("m", 1.0), ("mm", 1e3), ("µm", 1e6)):
        if peak * scale >= 1.0:
            return name, scale
    return "nm", 1e9


# kept for callers of the first version
_length_unit = length_unit


def _axes(ax: Any, figsize: tuple[float, float] = (9, 5)) -> Any:
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "plotting needs matplotlib (pip install matplotlib, or nlsdof[plot])"
        ) from e
    _, ax = plt.subplots(figsize=figsize)
    return ax


def _legend_outside(ax: Any) -> None:
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small",
                  borderaxespad=0.0)
    try:
        ax.figure.tight_layout()
    except Exception:  # pragma: no cover - layout is cosmetic
        pass


def _get(result: Any, key: str, default: Any = None) -> Any:
    try:
        return result[key]
    except (KeyError, TypeError, IndexError):
        return default


def fit(result: Any, ax: Any = None) -> Any:
    """The measured points (markers) and the fit's own model curves (lines)
    per level and sweep: amplitude (zero-to-peak, one length unit chosen
    from the data) against frequency (Hz). One colour per level, up-sweeps
    solid with filled dots, down-sweeps dashed with hollow circles; the
    legend sits outside the axes. Returns the Axes."""
    import numpy as np

    ax = _axes(ax)
    c = result.fitted_curves()
    level, sweep = np.asarray(c["level"]), np.asarray(c["sweep"])
    f = np.asarray(c["f_hz"], dtype=float)
    a = np.asarray(c["amplitude"], dtype=float)
    m = np.asarray(c["model_amplitude"], dtype=float)
    both = np.concatenate([a[np.isfinite(a)], m[np.isfinite(m)]])
    unit, scale = length_unit(float(np.max(both)) if both.size else 0.0)
    levels: list[str] = []
    keys: list[tuple[str, str]] = []
    for k in zip(level.tolist(), sweep.tolist()):
        if k not in keys:
            keys.append(k)
        if k[0] not in levels:
            levels.append(k[0])
    for lv, sw in keys:
        col = colour(levels.index(lv))
        st = sweep_style(sw)
        sel = (level == lv) & (sweep == sw)
        order = np.argsort(f[sel])
        ff = f[sel][order]
        ax.plot(ff, m[sel][order] * scale, color=col, linestyle=st["linestyle"],
                linewidth=1.6, label=f"{lv} {sw}")
        ax.plot(ff, a[sel][order] * scale, linestyle="none", marker=st["marker"],
                fillstyle=st["fillstyle"], color=col, markersize=3.5)
    # the sweep directions' styles in the legend (proxies, not drawn)
    from matplotlib.lines import Line2D

    handles, labels = ax.get_legend_handles_labels()
    for sw in ("up", "down"):
        if sw in set(sweep.tolist()):
            st = sweep_style(sw)
            handles.append(Line2D([], [], color=DARK, linestyle=st["linestyle"]))
            labels.append(f"model, sweep {sw}")
            handles.append(Line2D([], [], color=DARK, linestyle="none", marker="o",
                                  fillstyle=st["fillstyle"]))
            labels.append(f"data, sweep {sw}")
    ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              fontsize="small", borderaxespad=0.0)
    ax.set_xlabel("frequency f [Hz]")
    ax.set_ylabel(f"amplitude a [{unit}], zero-to-peak")
    ax.set_ylim(bottom=0.0)
    verdict = "" if result.adequate and result.converged else " (see result.warning)"
    ax.set_title(f"nlsdof fit: {result.to_dict()['model']}, cost {result.cost:.3e}{verdict}")
    ax.figure.tight_layout()
    return ax


def landscape(result: Any, ax: Any = None) -> Any:
    """The exponent landscape of a fit (`result`: a ``FitResult`` or its
    ``landscape()`` document) as the CLI's ``--landscape FILE.png``:
    log10(cost / min) over (rho, eta), low values bright (viridis), the grid
    minima ringed and the fitted exponents crossed; a 1-D profile when one
    exponent has a single node. A single node has nothing to draw:
    ValueError. Returns the Axes."""
    import numpy as np

    doc = result.landscape() if hasattr(result, "landscape") else result
    rho = np.asarray(doc["rho"], dtype=float)
    eta = np.asarray(doc["eta"], dtype=float)
    cost = np.array([[np.nan if v is None else v for v in row] for row in doc["cost"]],
                    dtype=float).reshape(len(eta), len(rho))
    positive = cost[np.isfinite(cost) & (cost > 0)]
    if rho.size * eta.size < 2:
        raise ValueError(
            "landscape: the fit has no free exponent, so its landscape is a single node "
            f"(rho {rho[0] if rho.size else 'nan'}, eta {eta[0] if eta.size else 'nan'}) "
            "and there is nothing to draw; free an exponent (e.g. model='generalised')"
        )
    cmin = positive.min() if positive.size else np.nan
    with np.errstate(invalid="ignore", divide="ignore"):
        val = np.log10(np.maximum(cost / cmin, 1.0))
    phase = " with phase" if doc.get("with_phase") else ""
    fitted = doc.get("fitted") or {}
    minima = doc.get("minima") or []
    ax = _axes(ax, (9, 6) if rho.size > 1 and eta.size > 1 else (9, 5))
    if rho.size > 1 and eta.size > 1:
        mesh = ax.pcolormesh(rho, eta, val, cmap="viridis_r", shading="nearest")
        bar = ax.figure.colorbar(mesh, ax=ax)
        bar.set_label("log10(cost / min)")
        ax.plot([m["rho"] for m in minima], [m["eta"] for m in minima], linestyle="none",
                marker="o", markersize=9, fillstyle="none", markeredgewidth=2,
                color="white", markeredgecolor="white", label="grid minima")
        if fitted:
            ax.plot([fitted["rho"]], [fitted["eta"]], linestyle="none", marker="x",
                    markersize=11, markeredgewidth=3, color="red",
                    label="fitted (output error)")
        ax.set_xlabel("rho (stiffness exponent)")
        ax.set_ylabel("eta (damping exponent)")
        ax.set_title(f"Exponent landscape: log10(cost / min), equation error{phase}")
        # the legend under the map, off the cells (white rings drawn black)
        leg = ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2,
                        fontsize="small", frameon=False)
        for h in leg.legend_handles if hasattr(leg, "legend_handles") else leg.legendHandles:
            if getattr(h, "get_markeredgecolor", None) and h.get_markeredgecolor() == "white":
                h.set_markeredgecolor("black")
        ax.figure.tight_layout()
        return ax
    along_rho = rho.size > 1
    xs = rho if along_rho else eta
    v = val[0, :] if along_rho else val[:, 0]
    name = "rho (stiffness exponent)" if along_rho else "eta (damping exponent)"
    ax.plot(xs, v, color=colour(0), linewidth=2, label="landscape (coefficients optimised)")
    mx = [m["rho"] if along_rho else m["eta"] for m in minima]
    my = [float(np.interp(x, xs, v)) for x in mx]
    ax.plot(mx, my, linestyle="none", marker="o", fillstyle="none", markersize=9,
            color=colour(0), label="grid minima")
    if fitted:
        ax.axvline(fitted["rho"] if along_rho else fitted["eta"], color=colour(1),
                   linestyle=(0, (3.5, 2.0)), linewidth=2, label="fitted (output error)")
    ax.set_xlabel(name)
    ax.set_ylabel("log10(cost / min)")
    ax.set_title(f"Exponent profile: log10(cost / min), equation error{phase}")
    _legend_outside(ax)
    return ax


def spectrogram(spec: Any, ax: Any = None, dynamic_range_db: float = 80.0) -> Any:
    """An STFT spectrogram as the CLI's ``spectrogram --plot`` heat map:
    time (s) across, frequency (Hz) up, colour the level in dB below the
    largest magnitude over `dynamic_range_db` dB (viridis). Returns the
    Axes."""
    import numpy as np

    ax = _axes(ax)
    t = np.asarray(spec.times, dtype=float)
    f = np.asarray(spec.frequencies, dtype=float)
    mag = np.asarray(spec.magnitude, dtype=float)
    top = np.nanmax(mag) if mag.size else 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        db = 20.0 * np.log10(mag / top)
    db = np.maximum(db, -dynamic_range_db)
    mesh = ax.pcolormesh(t, f, db.T, cmap="viridis", shading="nearest",
                         vmin=-dynamic_range_db, vmax=0.0)
    bar = ax.figure.colorbar(mesh, ax=ax)
    bar.set_label("level, 20 log10(|X| / max) [dB]")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("frequency f [Hz]")
    ax.set_title("STFT spectrogram")
    ax.figure.tight_layout()
    return ax


def decay(result: Any, x: Any = None, ax: Any = None, what: str = "envelope",
          column: str = "x", unit: str | None = None) -> Any:
    """A panel of the CLI's ``decay --plot`` figure from the result of
    ``nlsdof.decay`` (and the record `x` it analysed, optional):

    * ``what="envelope"``: the record (grey, mean removed), its Hilbert
      envelope and the fitted model's envelope (from the end of its Hilbert
      edge transient) against time (s);
    * ``what="backbone"``: frequency (Hz) of each amplitude bin and the
      fitted backbone;
    * ``what="damping"``: decay rate -d ln a/dt (1/s) against amplitude, and
      the fitted damping curve.

    Amplitude axes name the `column` and its `unit` (default "unit as
    recorded"). Returns the Axes."""
    import numpy as np

    unit = unit or "unit as recorded"
    ax = _axes(ax, (10, 4))
    fs = float(result["fs_hz"])
    amp_label = f"amplitude of {column} [{unit}]"
    curves = _get(result, "fitted_curves") or {}
    if what == "envelope":
        if x is not None:
            xx = np.asarray(x, dtype=float)
            step = max(len(xx) // 20000, 1)
            t = np.arange(len(xx))[::step] / fs
            ax.plot(t, xx[::step] - xx.mean(), color=GREY, linewidth=0.6, label="record")
        t = np.asarray(result["t"], dtype=float)
        env = np.asarray(result["envelope"], dtype=float)
        ax.plot(t, env, color=colour(0), linewidth=2, label="Hilbert envelope")
        model = np.asarray(result["model_envelope"], dtype=float)
        edge = int(_get(result, "model_envelope_edge", 0) or 0)
        n = min(len(model), len(t))
        ax.plot(t[edge:n], model[edge:n], color=colour(1), linewidth=2,
                label="fitted model's envelope")
        ax.set_xlabel("time t [s]")
        ax.set_ylabel(f"{column} [{unit}], mean removed")
        ax.set_title("record, Hilbert envelope and the fitted model's envelope")
    elif what == "backbone":
        bb = result["backbone"]
        ax.plot([p["f_hz"] for p in bb], [p["amplitude"] for p in bb], linestyle="none",
                marker="o", color=colour(0), label="Hilbert, per bin")
        if curves:
            ax.plot(curves["f_hz"], curves["amplitude"], color=colour(1), linewidth=2,
                    label="fitted")
        ax.set_xlabel("frequency f [Hz]")
        ax.set_ylabel(amp_label)
        ax.set_title("backbone f(a)")
    elif what == "damping":
        bb = result["backbone"]
        ax.plot([p["amplitude"] for p in bb], [p["decay_rate"] for p in bb], linestyle="none",
                marker="o", color=colour(0), label="Hilbert, per bin")
        if curves:
            a = np.asarray(curves["amplitude"], dtype=float)
            r = np.asarray(curves["decay_rate"], dtype=float)
            ok = np.isfinite(r) & (a > 0)
            ax.plot(a[ok], r[ok], color=colour(1), linewidth=2, label="fitted")
        ax.set_xlabel(amp_label)
        ax.set_ylabel("decay rate λ = -d ln a/dt [1/s]")
        ax.set_title("damping curve")
    else:
        raise ValueError(f"what {what!r}: use \"envelope\", \"backbone\" or \"damping\"")
    _legend_outside(ax)
    return ax


def fit_time(result: Any, y: Any, ax: Any = None) -> Any:
    """The output-error time fit (the result of ``nlsdof.fit_time`` and the
    measured output `y`, m): the measured output (grey) and the model output
    over the estimation range and each test range (one colour each, tests
    dashed), in one length unit chosen from the data, against time (s).
    Returns the Axes."""
    import numpy as np

    ax = _axes(ax, (10, 4.5))
    fs = float(result["fs_hz"])
    yy = np.asarray(y, dtype=float)
    ranges = [("estimation", result["estimation"])] + [
        (f"test {i + 1}", t) for i, t in enumerate(result.get("tests") or [])
    ]
    lo = min(int(r["range"][0]) for _, r in ranges)
    hi = max(int(r["range"][1]) for _, r in ranges)
    finite = yy[lo:hi][np.isfinite(yy[lo:hi])]
    unit, scale = length_unit(float(np.max(np.abs(finite))) if finite.size else 0.0)
    t = np.arange(len(yy)) / fs
    ax.plot(t[lo:hi], yy[lo:hi] * scale, color=GREY, linewidth=1.0, label="measured")
    for i, (name, r) in enumerate(ranges):
        a, b = int(r["range"][0]), int(r["range"][1])
        ym = r.get("y_model")
        if ym is None:
            continue
        ym = np.asarray(ym, dtype=float)
        n = min(len(ym), b - a)
        ax.plot(t[a:a + n], ym[:n] * scale, color=colour(i), linewidth=1.2,
                linestyle="-" if i == 0 else (0, (3.5, 2.0)),
                label=f"model, {name} (RMS {r['rms']:.3g} m)")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(f"output y [{unit}]")
    ax.set_title(f"nlsdof fit_time: {result['model']}, measured and model output")
    _legend_outside(ax)
    return ax


def linear_id(result: Any, ax: Any = None, what: str = "magnitude") -> Any:
    """A panel of the CLI's ``linear-id --plot`` figure from the result of
    ``nlsdof.linear_id``: ``what="magnitude"`` |H| (log scale, in the FRF's
    unit), ``"phase"`` (deg) against frequency (Hz), measured points and the
    vector fit; ``"nyquist"`` the mobility (velocity per input) of the data
    and the fit. Returns the Axes."""
    import numpy as np

    ax = _axes(ax, (8, 5))
    f = np.asarray(result["f_hz"], dtype=float)
    h = np.asarray(result["frf"], dtype=complex)
    ff = _get(result, "fit_f_hz")
    hf = _get(result, "fit_frf")
    unit = result.get("frf_unit", "")
    has_phase = bool(np.all(np.isfinite(h.imag))) if h.size else False
    if what == "magnitude":
        ax.semilogy(f, np.abs(h) if has_phase else h.real, linestyle="none", marker="o",
                    fillstyle="none", markersize=3, color=colour(0), label="measured")
        if ff is not None:
            ax.semilogy(ff, np.abs(hf), color=colour(1), linewidth=2, label="vector fit")
        ax.set_xlabel("frequency f [Hz]")
        ax.set_ylabel(f"|H| [{unit}]")
        ax.set_title("Measured (points) and fitted (line) FRF")
    elif what == "phase":
        if has_phase:
            ax.plot(f, np.degrees(np.angle(h)), linestyle="none", marker="o", fillstyle="none",
                    markersize=3, color=colour(0), label="measured")
        if ff is not None:
            ax.plot(ff, np.degrees(np.angle(hf)), color=colour(1), linewidth=2,
                    label="vector fit")
        ax.set_ylim(-180, 180)
        ax.set_xlabel("frequency f [Hz]")
        ax.set_ylabel("phase of H [deg]")
        ax.set_title("Phase")
    elif what == "nyquist":
        p = int(result.get("output_power", 0))
        mu = result.get("mobility_unit", "")

        def mobility(freq: Any, z: Any) -> Any:
            s = 2j * np.pi * np.asarray(freq, dtype=float)
            return z * s ** (1 - p)

        if has_phase:
            y = mobility(f, h)
            ax.plot(y.real, y.imag, linestyle="none", marker="o", fillstyle="none",
                    markersize=3, color=colour(0), label="data")
        if ff is not None:
            y = mobility(ff, hf)
            ax.plot(y.real, y.imag, color=colour(1), linewidth=2, label="fit")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(f"Re Y [{mu}]")
        ax.set_ylabel(f"Im Y [{mu}]")
        ax.set_title("Nyquist plot of the mobility")
    else:
        raise ValueError(f"what {what!r}: use \"magnitude\", \"phase\" or \"nyquist\"")
    _legend_outside(ax)
    return ax
