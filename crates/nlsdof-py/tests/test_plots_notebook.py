"""The matplotlib figures (nlsdof.plot, `plot` methods), the example that
draws each of them (examples/python/plots.py) and the quickstart notebook
(examples/quickstart.ipynb), executed top to bottom with nbclient.

matplotlib, nbclient, nbformat and ipykernel are installed by .ci/run: a
missing one fails these tests (nothing is skipped silently).
"""

import pathlib
import subprocess
import sys

import numpy as np

import nlsdof
import nlsdof.plot

ROOT = pathlib.Path(__file__).resolve().parents[3]


def _agg():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _duffing_data(down=True):
    wn = 2 * np.pi * 10.0
    m = nlsdof.Model(1.0, wn**2, 0.02 * wn, nonlinear_stiffness=(2.5e6, 2.0))
    f = np.linspace(8.5, 12.0, 30)
    cols = {"level": [], "gamma": [], "f_hz": [], "amplitude": [], "sweep": []}
    for i, g in enumerate((0.1, 0.3)):
        for d in ("up", "down") if (down and i == 1) else ("up",):
            s = m.sweep(g, f, d)
            cols["level"] += [str(g)] * len(f)
            cols["gamma"] += [g] * len(f)
            cols["f_hz"] += list(f)
            cols["amplitude"] += list(s.amplitude)
            cols["sweep"] += [d] * len(f)
    return m, cols


def test_conventions_match_the_cli():
    # 20 distinct colours, the CLI's palette, one length unit rule
    assert len(set(nlsdof.plot.COLOURS)) == 20
    assert nlsdof.plot.COLOURS[0] == "#1f77b4" and nlsdof.plot.colour(20) == "#1f77b4"
    assert nlsdof.plot.length_unit(0.02) == ("mm", 1e3)
    assert nlsdof.plot.length_unit(2.0) == ("m", 1.0)
    assert nlsdof.plot.length_unit(2e-5) == ("µm", 1e6)
    up, down = nlsdof.plot.sweep_style("up"), nlsdof.plot.sweep_style("down")
    assert up["linestyle"] == "-" and down["linestyle"] != "-"
    assert up["fillstyle"] == "full" and down["fillstyle"] == "none"


def test_fit_and_landscape_plots():
    plt = _agg()
    _, cols = _duffing_data()
    r = nlsdof.fit(cols, "generalised-stiffness", grid=[12, 1])
    fig, ax = plt.subplots()
    assert r.plot(ax=ax) is ax
    assert ax.get_ylabel() == "amplitude a [mm], zero-to-peak"
    styles = {ln.get_label(): ln.get_linestyle() for ln in ax.get_lines()}
    assert styles["0.3 up"] == "-" and styles["0.3 down"] != "-", styles
    # the legend sits outside the axes
    leg = ax.get_legend()
    fig.canvas.draw()
    assert leg.get_window_extent().x0 >= ax.get_window_extent().x1
    plt.close("all")
    ax = r.plot_landscape()
    assert ax.get_xlabel() == "rho (stiffness exponent)"
    assert len(ax.get_lines()[0].get_xdata()) == 12
    doc = r.landscape()
    assert len(doc["rho"]) == 12 and len(doc["eta"]) == 1
    # a single node is refused in one line
    d = nlsdof.fit(cols, "duffing")
    try:
        d.plot_landscape()
    except ValueError as e:
        assert "single node" in str(e)
    else:
        raise AssertionError("a one-node landscape was drawn")
    plt.close("all")


def test_decay_fit_time_linear_id_and_spectrogram_plots():
    plt = _agg()
    m, _ = _duffing_data()
    fs = 1000.0
    x = np.asarray(m.simulate(np.zeros(20000), fs=fs, x0=1e-3)[0])
    d = nlsdof.decay(x, fs, t_start=0.0)
    ax = d.plot(x, what="envelope", column="x", unit="m")
    assert ax.get_ylabel() == "x [m], mean removed"
    # the model envelope starts after its Hilbert edge transient: no spike
    model = ax.get_lines()[2].get_ydata()
    env = np.asarray(d["envelope"])
    assert np.max(model) <= 1.05 * np.max(env)
    for what, label in (("backbone", "amplitude of x [m]"), ("damping", "decay rate")):
        ax = nlsdof.plot.decay(d, what=what, column="x", unit="m")
        assert label in ax.get_ylabel() or label in ax.get_xlabel()
    plt.close("all")
    t = np.arange(4000) / fs
    u = 2.0 * np.sin(2 * np.pi * (7.0 + 1.0 * t) * t)
    y = np.asarray(m.simulate(u, fs=fs)[0])
    tf = nlsdof.fit_time(u, y, fs, model="duffing", fit_range=[0, 2000], tests=[[2000, 4000]])
    ax = tf.plot(y)
    assert ax.get_ylabel() == "output y [mm]"
    assert len(ax.get_lines()) == 3  # measured, estimation, test
    plt.close("all")
    ff = np.linspace(7.0, 13.0, 200)
    s = 2j * np.pi * ff
    wn = 2 * np.pi * 10.0
    lin = nlsdof.linear_id(ff, 1.0 / (s**2 + 0.02 * wn * s + wn**2))
    ax = lin.plot(what="magnitude")
    assert ax.get_ylabel() == "|H| [m/(m/s²)]"
    assert nlsdof.plot.linear_id(lin, what="nyquist").get_xlabel() == "Re Y [(m/s)/(m/s²)]"
    plt.close("all")
    ax = nlsdof.spectrogram(y, fs).plot()
    assert ax.get_xlabel() == "time t [s]" and ax.get_ylabel() == "frequency f [Hz]"
    plt.close("all")


def test_the_plots_example_draws_every_figure(tmp_path):
    r = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "python" / "plots.py"), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert r.returncode == 0, r.stderr
    for name in ("fit", "landscape", "decay", "fit_time", "linear_id", "spectrogram", "report_plots"):
        p = tmp_path / f"{name}.png"
        assert p.is_file() and p.read_bytes().startswith(b"\x89PNG"), name


def test_the_quickstart_notebook_runs_top_to_bottom():
    import nbformat
    from nbclient import NotebookClient

    path = ROOT / "examples" / "quickstart.ipynb"
    nb = nbformat.read(str(path), as_version=4)
    NotebookClient(
        nb,
        timeout=900,
        kernel_name="python3",
        resources={"metadata": {"path": str(path.parent)}},
    ).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    text = "".join(o.get("text", "") for o in outputs)
    assert "beam set" in text  # says which data it used
