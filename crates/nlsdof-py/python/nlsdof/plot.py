"""matplotlib figures of nlsdof results (an optional extra:
``pip install nlsdof[plot]``). Each function takes ``ax=None`` (a new figure
when None) and returns the Axes, as pandas and seaborn plotting do.
"""


def _axes(ax):
    if ax is not None:
        return ax
    try:
        import matplotlib.pyplot as plt
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError(
            "plotting needs matplotlib (pip install matplotlib, or nlsdof[plot])"
        ) from e
    _, ax = plt.subplots(figsize=(9, 5))
    return ax


def _length_unit(peak):
    """One length unit for a figure, from the data's magnitude (m)."""
    for name, scale in (("m", 1.0), ("mm", 1e3), ("um", 1e6), ("nm", 1e9)):
        if peak * scale >= 1.0:
            return name, scale
    return "nm", 1e9


def fit(result, ax=None):
    """The measured points (dots) and the fit's own model curves (lines) per
    level and sweep: amplitude (zero-to-peak, one length unit chosen from the
    data) against frequency (Hz). Up-sweeps solid, down-sweeps dashed; the
    legend sits outside the axes. Returns the Axes."""
    import numpy as np

    ax = _axes(ax)
    c = result.fitted_curves()
    level, sweep = np.asarray(c["level"]), np.asarray(c["sweep"])
    f, a, m = c["f_hz"], c["amplitude"], c["model_amplitude"]
    unit, scale = _length_unit(max(np.max(a), np.max(m)))
    keys = []
    for k in zip(level, sweep):
        if k not in keys:
            keys.append(k)
    colours = [ax._get_lines.get_next_color() for _ in {k[0] for k in keys}]
    by_level = {}
    for lv, sw in keys:
        col = by_level.setdefault(lv, colours[len(by_level) % len(colours)])
        sel = (level == lv) & (sweep == sw)
        order = np.argsort(f[sel])
        ff = f[sel][order]
        ax.plot(ff, m[sel][order] * scale, color=col, linestyle="-" if sw == "up" else "--",
                label=f"{lv} ({sw}) model")
        ax.plot(ff, a[sel][order] * scale, "o", color=col, markersize=3, label=f"{lv} ({sw}) measured")
    ax.set_xlabel("frequency f [Hz]")
    ax.set_ylabel(f"amplitude [{unit}], zero-to-peak")
    verdict = "" if result.adequate and result.converged else " (see result.warning)"
    ax.set_title(f"nlsdof fit: {result.to_dict()['model']}, cost {result.cost:.3e}{verdict}")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.figure.tight_layout()
    return ax
