"""Notebook display: the documents are dicts (equal to the CLI's) that
Jupyter shows as a table of parameters with values, 95 % intervals, SI
units and the status; Simulation and Spectrogram show their key numbers."""

import pathlib
import pickle
import re

import numpy as np
import pytest

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]


def cells(html):
    return re.findall(r"<td>(.*?)</td>", html)


def test_decay_document_shows_parameters_intervals_units_and_status():
    t = np.arange(20000) / 1000.0
    wn = 2 * np.pi * 20
    x = np.exp(-0.01 * wn * t) * np.cos(wn * np.sqrt(1 - 1e-4) * t)
    r = nlsdof.decay(x, fs=1000.0)
    assert isinstance(r, dict) and dict(r) == r
    h = r._repr_html_()
    assert h.startswith("<div><b>nlsdof decay</b>") and "adequate" in h
    c = cells(h)
    assert "damping: delta" in c and "stiffness: alpha" in c
    # the interval of delta, as in the document
    d = r["damping_fit"]["parameters"][0]
    assert f"[{d['lower']:.6g}, {d['upper']:.6g}]" in c
    # pickles as a dict of the same content
    back = pickle.loads(pickle.dumps(r))
    assert type(back) is type(r) and back.kind == "decay" and list(back) == list(r)
    assert back["damping_fit"] == r["damping_fit"]


def test_fit_time_and_linear_id_documents_show_units():
    u = np.random.default_rng(0).standard_normal(1000)
    y, _ = nlsdof.Model(1.0, (2 * np.pi * 5) ** 2, 2.0).simulate(u, fs=200.0)
    r = nlsdof.fit_time(u, y, 200.0, model="linear")
    h = r._repr_html_()
    assert "nlsdof fit_time: linear" in h and "converged" in h
    c = cells(h)
    i = c.index("alpha")
    assert c[i + 3] == "1/s^2" and c[i + 2].startswith("[")
    f = np.linspace(5.0, 15.0, 201)
    w = 2 * np.pi * f
    doc = nlsdof.linear_id(f, 1 / ((2 * np.pi * 10) ** 2 - w**2 + 2j * w))
    c = cells(doc._repr_html_())
    assert c[c.index("f_n_hz") + 3] == "Hz" and c[c.index("delta") + 3] == "1/s"


def test_compare_and_frf_estimate_documents():
    x = np.random.default_rng(2).standard_normal(4096)
    r = nlsdof.frf_estimate(x, x, fs=100.0, segment=512)
    h = r._repr_html_()
    assert "nlsdof frf_estimate" in h
    c = cells(h)
    assert c[c.index("fs") + 3] == "Hz"
    wing = nlsdof.Model.from_toml(ROOT / "examples" / "har-wing.toml")
    f = np.linspace(5.3, 5.5, 25)
    data = {"level": ["1"] * 25, "gamma": [0.41] * 25, "f_hz": f, "amplitude": wing.sweep(0.41, f).amplitude}
    r = nlsdof.compare(data, models="linear,duffing")
    c = cells(r._repr_html_())
    assert c[0] == "linear" and c[4] == "duffing" and c[2] == "True"


def test_simulation_and_spectrogram_html():
    m = nlsdof.Model(1.0, 100.0, 0.5)
    sim = m.simulate(np.ones(200), fs=100.0)
    h = sim._repr_html_()
    assert "nlsdof Simulation" in h and "ok" in h
    c = cells(h)
    assert float(c[c.index("max |x|") + 1]) == pytest.approx(np.max(np.abs(sim.x)), rel=1e-6)
    assert c[c.index("max |v|") + 2] == "m/s"
    s = nlsdof.spectrogram(np.sin(np.arange(3000) / 3.0), fs=100.0)
    h = s._repr_html_()
    assert "nlsdof Spectrogram" in h and "<td>Hz</td>" in h
