"""Readers (LVM, Polytec, MAT) and the CLI's workflows in Python
(frf_estimate, compare, signal).

Oracles, independent of the library's readers: the files parsed here with
plain Python, scipy.io.loadmat for MAT files, scipy.signal for the Welch
estimates, and the CLI's own output (`--json` documents and the files it
writes) on the same inputs.
"""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]
SHARED = ROOT.parent / "shared" / "data"
LVM = SHARED / "magnetomechanical-sdof-decay-frid" / "decay_f_42p05_ampl_2p0_0.lvm"
IMPACT = SHARED / "clamped-beam-duffing-catarinaluz" / "cc_beam_no_magnet_impact"
SWEEP = SHARED / "clamped-beam-duffing-catarinaluz" / "cc_beam_no_magnet_24C" / "frf_0.04g.txt"
SILVERBOX = SHARED / "silverbox" / "SNLS80mV.mat"
WING = ROOT / "examples" / "har-wing.toml"

needs_shared = pytest.mark.skipif(not SHARED.exists(), reason="../shared/data is not beside the repo")


@pytest.fixture(scope="session")
def cli():
    exe = pathlib.Path(os.environ.get("NLSDOF_CLI", ROOT / "target" / "release" / "nlsdof"))
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "-p", "nlsdof-cli"], cwd=ROOT, check=True)
    return str(exe)


def run_cli(cli, *args):
    r = subprocess.run([cli, *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r.stdout


def one_line_value_error(call, *words):
    with pytest.raises(ValueError) as e:
        call()
    msg = str(e.value)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, msg
    return msg


# ---------------------------------------------------------------- readers


def parse_lvm(path):
    """The LVM by hand: the rows after the second End_of_Header line."""
    lines = pathlib.Path(path).read_text().splitlines()
    ends = [i for i, l in enumerate(lines) if l.startswith("***End_of_Header***")]
    names = lines[ends[1] + 1].split("\t")
    rows = [l.split("\t") for l in lines[ends[1] + 2 :] if l.strip()]
    return names, rows


@needs_shared
def test_read_lvm_equals_the_text_and_leaves_out_short_channels():
    names, rows = parse_lvm(LVM)
    d = nlsdof.read_lvm(LVM)
    # the channels with a number on every row, in file order
    full = [
        n
        for i, n in enumerate(names)
        if n and all(i < len(r) and r[i].strip() for r in rows)
    ]
    assert list(d) == full
    assert "Untitled" not in d and "Comment" not in d and "X_Value" in d
    for n in full:
        i = names.index(n)
        want = np.array([float(r[i]) for r in rows])
        assert d[n].dtype == np.float64
        assert np.array_equal(d[n], want), n
    # chosen columns, by name (case-insensitive) or 0-based index
    c = nlsdof.read_lvm(LVM, columns=["strain_0", "0"])
    assert list(c) == ["Strain_0", "X_Value"]
    assert np.array_equal(c["Strain_0"], d["Strain_0"])


def test_read_lvm_errors_name_file_line_and_column(tmp_path):
    p = tmp_path / "a.lvm"
    p.write_text(
        "LabVIEW Measurement\t\n***End_of_Header***\t\n\nChannels\t1\n***End_of_Header***\t\n"
        "X_Value\tV\tComment\n0.0\t1.5\t\n0.001\tabc\t\n"
    )
    one_line_value_error(lambda: nlsdof.read_lvm(p), "a.lvm", "line 8", '"V"', "abc")
    one_line_value_error(lambda: nlsdof.read_lvm(p, columns=["W"]), 'no column "W"', "X_Value (0)")
    one_line_value_error(lambda: nlsdof.read_lvm(tmp_path / "none.lvm"), "none.lvm")
    p.write_text(p.read_text().replace("abc", "2.5"))
    d = nlsdof.read_lvm(p)
    assert list(d) == ["X_Value", "V"] and list(d["V"]) == [1.5, 2.5]


@needs_shared
def test_read_polytec_equals_the_text():
    path = IMPACT / "mec-t1-velocity.txt"
    lines = path.read_text(encoding="latin-1").splitlines()
    signal = next(l for l in lines if l.startswith("Signal:"))
    name = signal.split("\t")[1].split(" - ")[1].strip()
    units = next(i for i, l in enumerate(lines) if l.startswith("[ s ]"))
    rows = [l.split("\t") for l in lines[units + 1 :] if l.strip()]
    d = nlsdof.read_polytec(path)
    assert list(d) == ["t", name]
    assert np.array_equal(d["t"], [float(r[0]) for r in rows])
    assert np.array_equal(d[name], [float(r[1]) for r in rows])
    fs = 1.0 / (d["t"][1] - d["t"][0])
    assert fs == pytest.approx(10000.0, rel=1e-9)


def test_read_polytec_refuses_other_files_with_one_line(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("t,x\n0,1\n1,2\n")
    one_line_value_error(lambda: nlsdof.read_polytec(p), "x.csv", "not a Polytec ASCII export")
    p.write_text("Source File Name:\tt3\nSignal:\tTime - Ref1 Force - Samples\n\nTime\tTime Signal\n[ s ]\t[ N ]\n0\t1\n0.1\t2\n0.5\t3\n")
    one_line_value_error(lambda: nlsdof.read_polytec(p), "x.csv", "uniform")


@needs_shared
def test_read_polytec_sweep_equals_the_text_and_the_beam_reader():
    runs = nlsdof.read_polytec_sweep(SWEEP)
    lines = SWEEP.read_text(encoding="latin-1").splitlines()[2:]
    rows = [[float(f.strip().replace(",", ".")) for f in l.split("\t") if f.strip()] for l in lines if l.strip()]
    assert len(runs) == 2
    for j, run in enumerate(runs):
        assert np.array_equal(run["f_hz"], [r[0] for r in rows])
        assert np.array_equal(run["amplitude"], [r[1 + 2 * j] for r in rows])
        assert np.array_equal(run["phase_deg"], [r[2 + 2 * j] for r in rows])


@needs_shared
def test_read_mat_equals_scipy_loadmat_on_silverbox():
    scipy_io = pytest.importorskip("scipy.io")
    d = nlsdof.read_mat(SILVERBOX)
    ref = {k: v for k, v in scipy_io.loadmat(SILVERBOX).items() if not k.startswith("__")}
    assert sorted(d) == sorted(ref)
    for k, v in ref.items():
        assert d[k].shape == v.shape and d[k].dtype == np.float64
        assert np.array_equal(d[k], v.astype(np.float64)), k
    assert list(nlsdof.read_mat(SILVERBOX, variables=["V2"])) == ["V2"]


def test_read_mat_shapes_compression_and_errors(tmp_path):
    scipy_io = pytest.importorskip("scipy.io")
    a = np.arange(6.0).reshape(2, 3)
    p = tmp_path / "m.mat"
    for compress in (False, True):
        scipy_io.savemat(p, {"a": a, "fs": 100.0, "z": np.array([1 + 2j]), "i": np.int16([[3, -4]])}, do_compression=compress)
        d = nlsdof.read_mat(p)
        assert sorted(d) == ["a", "fs", "i"]  # the complex array is left out
        assert np.array_equal(d["a"], a) and d["a"].shape == (2, 3)
        assert d["fs"].shape == (1, 1) and d["fs"][0, 0] == 100.0
        assert np.array_equal(d["i"], [[3.0, -4.0]])
    one_line_value_error(lambda: nlsdof.read_mat(p, variables=["z"]), "m.mat", '"z"', "complex")
    one_line_value_error(lambda: nlsdof.read_mat(p, variables=["q"]), "m.mat", '"q"', "a[2, 3]")
    t = tmp_path / "t.mat"
    t.write_text("t,x\n0,1\n")
    one_line_value_error(lambda: nlsdof.read_mat(t), "t.mat", "not a MAT file")


# ----------------------------------------------------------- frf_estimate


@needs_shared
@pytest.mark.parametrize(
    "kwargs, flags",
    [
        ({"method": "ratio", "f_min": 50.0, "f_max": 400.0}, ["--method", "ratio", "--f-min", "50", "--f-max", "400"]),
        ({"segment": 8192, "window": "hamming", "f_max": 1000.0}, ["--segment", "8192", "--window", "hamming", "--f-max", "1000"]),
        ({"method": "h2", "overlap": 0.25, "symmetric_window": True}, ["--method", "h2", "--overlap", "0.25", "--symmetric-window"]),
    ],
)
def test_frf_estimate_equals_the_cli(cli, tmp_path, kwargs, flags):
    x, y = IMPACT / "mec-t1-force.txt", IMPACT / "mec-t1-velocity.txt"
    out_cli, out_py = tmp_path / "cli.csv", tmp_path / "py.csv"
    doc = json.loads(run_cli(cli, "frf-estimate", "--input", x, "--output-file", y, *flags, "--out", out_cli, "--json"))
    r = nlsdof.frf_estimate(x, y, out=out_py, **kwargs)
    arrays = {k: r.pop(k) for k in ("f_hz", "frf", "coherence")}
    doc["out"] = str(out_py)
    assert r == doc
    assert out_py.read_bytes() == out_cli.read_bytes()
    rows = np.loadtxt(out_cli, delimiter=",", skiprows=1)
    assert np.array_equal(arrays["f_hz"], rows[:, 0])
    assert np.array_equal(arrays["frf"].real, rows[:, 1]) and np.array_equal(arrays["frf"].imag, rows[:, 2])
    if doc["method"] == "ratio":
        assert arrays["coherence"] is None
    else:
        assert np.array_equal(arrays["coherence"], rows[:, 5])
    # the same numbers from the arrays the readers give
    fx, fy = nlsdof.read_polytec(x), nlsdof.read_polytec(y)
    r2 = nlsdof.frf_estimate(fx["Ref1 Force"], list(fy.values())[1], fs=doc["fs"], **kwargs)
    assert np.array_equal(r2["frf"], arrays["frf"])


def test_frf_estimate_h1_h2_and_coherence_equal_scipy():
    sig = pytest.importorskip("scipy.signal")
    rng = np.random.default_rng(7)
    fs, n = 2000.0, 20000
    x = rng.standard_normal(n)
    b, a = sig.butter(2, 0.2)
    y = sig.lfilter(b, a, x) + 0.05 * rng.standard_normal(n)
    nper = 1024
    f, pxx = sig.welch(x, fs, window="hann", nperseg=nper, noverlap=nper // 2, detrend="constant")
    _, pyy = sig.welch(y, fs, window="hann", nperseg=nper, noverlap=nper // 2, detrend="constant")
    _, pxy = sig.csd(x, y, fs, window="hann", nperseg=nper, noverlap=nper // 2, detrend="constant")
    for method, h_ref in (("h1", pxy / pxx), ("h2", pyy / np.conj(pxy))):
        r = nlsdof.frf_estimate(x, y, fs=fs, method=method, segment=nper)
        keep = f > 0
        assert np.allclose(r["f_hz"], f[keep], rtol=0, atol=1e-9)
        assert np.allclose(r["frf"], h_ref[keep], rtol=1e-9, atol=1e-12)
        coh = np.abs(pxy) ** 2 / (pxx * pyy)
        assert np.allclose(r["coherence"], coh[keep], rtol=1e-9, atol=1e-12)
        assert r["averages"] == (n - nper) // (nper // 2) + 1
        assert r["mean_coherence"] == pytest.approx(np.mean(coh[keep]), rel=1e-12)


def test_frf_estimate_bad_input_is_one_line():
    x = np.sin(np.arange(64.0))
    one_line_value_error(lambda: nlsdof.frf_estimate(x, x, fs=10.0, method="h3"), "method", "h3")
    one_line_value_error(lambda: nlsdof.frf_estimate(x, x), "fs")
    one_line_value_error(lambda: nlsdof.frf_estimate(x, x[:-1], fs=10.0), "64 samples", "63")
    one_line_value_error(lambda: nlsdof.frf_estimate(x, x, fs=10.0, f_min=3.0, f_max=2.0), "f_min 3", "f_max 2")
    one_line_value_error(lambda: nlsdof.frf_estimate(x, x, fs=10.0, overlap=1.0), "overlap 1")
    one_line_value_error(lambda: nlsdof.frf_estimate(np.zeros(64), x, fs=10.0), "no power")
    one_line_value_error(lambda: nlsdof.frf_estimate(x, x, fs=10.0, window="kaiser"), "kaiser")
    one_line_value_error(lambda: nlsdof.frf_estimate("no-such.csv", fs=10.0), "no-such.csv")


# ---------------------------------------------------------------- compare


def wing_columns(levels=(0.41, 0.81), steps=25, noise=0.01, seed=5):
    model = nlsdof.Model.from_toml(WING)
    rng = np.random.default_rng(seed)
    f = np.linspace(5.3, 5.5, steps)
    cols = {"level": [], "gamma": [], "f_hz": [], "amplitude": [], "sweep": []}
    for i, gamma in enumerate(levels):
        a = model.sweep(gamma=gamma, f_hz=f).amplitude * (1 + noise * rng.standard_normal(steps))
        cols["level"] += [str(i + 1)] * steps
        cols["gamma"] += [gamma] * steps
        cols["f_hz"] += list(f)
        cols["amplitude"] += list(a)
        cols["sweep"] += ["up"] * steps
    return cols


def write_columns(path, cols):
    with open(path, "w") as out:
        out.write("level,gamma,f_hz,amplitude,sweep\n")
        for l, g, f, a, s in zip(*(cols[k] for k in ("level", "gamma", "f_hz", "amplitude", "sweep"))):
            out.write(f"{l},{g!r},{float(f)!r},{float(a)!r},{s}\n")


def test_compare_equals_the_cli(cli, tmp_path):
    path = tmp_path / "d.csv"
    write_columns(path, wing_columns())
    doc = json.loads(run_cli(cli, "compare", path, "--models", "linear,duffing-quadratic", "--free", "gain", "--mass", "0.26699", "--json"))
    r = nlsdof.compare(str(path), models=["linear", "duffing-quadratic"], free="gain", mass=0.26699)
    assert r == doc
    assert [m["model"] for m in r["models"]] == ["linear", "duffing-quadratic"]
    # each model is fitted as fit fits it (the same numbers)
    single = nlsdof.fit(str(path), model="linear", free=["gain"], mass=0.26699).to_dict()
    for key in ("cost", "theta", "converged", "aic", "bic", "adequacy"):
        assert r["models"][0][key] == single[key], key


def test_compare_bad_input_is_one_line():
    cols = wing_columns(levels=(0.41,), steps=10)
    one_line_value_error(lambda: nlsdof.compare(cols, models="linear,nope"), "unknown model 'nope'")
    one_line_value_error(lambda: nlsdof.compare(cols, models=""), "no models")
    one_line_value_error(lambda: nlsdof.compare(cols, starts=0), "starts 0")
    one_line_value_error(lambda: nlsdof.compare(cols, free="zeta"), "free:", "zeta")
    one_line_value_error(lambda: nlsdof.compare(cols, sign="up"), 'sign "up"')
    one_line_value_error(lambda: nlsdof.compare(cols, mass=-1.0), "mass -1")


# ----------------------------------------------------------------- signal


def read_t_accel(path):
    rows = pathlib.Path(path).read_text().splitlines()
    assert rows[0] == "t,accel"
    t, a = zip(*((float(p) for p in r.split(",")) for r in rows[1:]))
    return np.array(t), np.array(a)


@pytest.mark.parametrize(
    "kind, kwargs, flags",
    [
        ("sine", {"freq": 5.0, "duration": 2.0, "phase_deg": 30.0}, ["--freq", "5", "--duration", "2", "--phase-deg", "30"]),
        ("chirp", {"f0": 4.5, "rate": 0.5, "f1": 6.0}, ["--f0", "4.5", "--rate", "0.5", "--f1", "6"]),
        ("chirp", {"chirp_kind": "log", "f0": 1.0, "f1": 10.0, "duration": 3.0}, ["--kind", "log", "--f0", "1", "--f1", "10", "--duration", "3"]),
        ("stepped-sine", {"f_min": 2.0, "f_max": 4.0, "steps": 5, "sweep": "down", "dwell_cycles": 3}, ["--f-min", "2", "--f-max", "4", "--steps", "5", "--sweep", "down", "--dwell-cycles", "3"]),
        ("stepped_sine", {"f_min": 2.0, "f_max": 4.0, "steps": 3, "dwell": 0.7}, ["--f-min", "2", "--f-max", "4", "--steps", "3", "--dwell", "0.7"]),
    ],
)
def test_signal_equals_the_cli_sample_for_sample(cli, tmp_path, kind, kwargs, flags):
    out_cli, out_py = tmp_path / "cli.csv", tmp_path / "py.csv"
    run_cli(cli, "signal", kind.replace("_", "-"), "--amplitude", "1.5", "--fs", "200", *flags, "--out", out_cli)
    s = nlsdof.signal(kind, amplitude=1.5, fs=200.0, out=out_py, **kwargs)
    t, a = read_t_accel(out_cli)
    assert np.array_equal(s["t"], t) and np.array_equal(s["accel"], a)
    assert out_py.read_bytes() == out_cli.read_bytes()


def test_signal_sine_is_the_closed_form():
    s = nlsdof.signal("sine", amplitude=2.0, fs=1000.0, freq=7.0, duration=1.0, phase_deg=45.0)
    t = np.arange(1001) / 1000.0
    assert np.array_equal(s["t"], t)
    assert np.allclose(s["accel"], 2.0 * np.sin(2 * np.pi * 7.0 * t + np.pi / 4), rtol=0, atol=1e-12)


def test_signal_bad_input_is_one_line():
    one_line_value_error(lambda: nlsdof.signal("sine", amplitude=1, fs=0, freq=1, duration=1), "fs 0 is not allowed", "> 0")
    one_line_value_error(lambda: nlsdof.signal("sine", amplitude=1, fs=10, duration=1), "needs freq")
    one_line_value_error(lambda: nlsdof.signal("chirp", amplitude=1, fs=10, f0=1, f1=2), "two of f1, rate, duration")
    one_line_value_error(lambda: nlsdof.signal("stepped-sine", amplitude=1, fs=10, f_min=1, f_max=2, steps=3), "dwell_cycles N or dwell")
    one_line_value_error(lambda: nlsdof.signal("stepped-sine", amplitude=1, fs=10, f_min=1, f_max=2, steps=1, dwell=1), "steps 1: need 2")
    one_line_value_error(lambda: nlsdof.signal("noise", amplitude=1, fs=10), 'kind "noise"')
    one_line_value_error(lambda: nlsdof.signal("sine", amplitude=1, fs=1e9, freq=1, duration=1e3), "too many")
    one_line_value_error(lambda: nlsdof.signal("sine", amplitude=1, fs=1e6, freq=1, duration=200), "too many for arrays")
