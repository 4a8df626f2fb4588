"""The newcomer's loop of README.md ("A beam set end to end"; issue 27: read,
fit, predict, plot, DataFrame, save, reload in at most 15 lines), run as
written: the exact code block, in a temporary directory whose `../shared`
is the repository's `../shared` (the block's data path is from the
repository root), with matplotlib's Agg backend. Needs pandas, matplotlib
and the beam data (all present in CI: nothing is skipped)."""

import os
import pathlib
import pickle
import re

import numpy as np

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]
SHARED = ROOT.parent / "shared"
HEADING = "A beam set end to end"


def readme_loop():
    """The first ```python block after the paragraph that starts with
    HEADING."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    start = text.index(HEADING)
    m = re.compile(r"^```python\n(.*?)^```", re.S | re.M).search(text, start)
    assert m, f"no python block after {HEADING!r} in README.md"
    return m.group(1)


def code_lines(block):
    return [
        line
        for line in block.splitlines()
        if line.strip() and not line.lstrip().startswith("#")
    ]


def test_the_loop_has_every_step_in_at_most_15_lines():
    block = readme_loop()
    lines = code_lines(block)
    assert len(lines) <= 15, f"{len(lines)} code lines:\n" + "\n".join(lines)
    # the steps the issue names, each a call of the library
    for step, call in {
        "read": "read_beam_dir(",
        "fit": "nlsdof.fit(",
        "predict": "r.predict(",
        "DataFrame": "to_dataframe()",
        "plot": "r.plot()",
        "save": "to_toml()",
        "reload": "Model.from_toml(",
    }.items():
        assert call in block, f"the loop does not {step} ({call!r})"


def test_the_readme_loop_runs_and_its_result_reloads(tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    assert (SHARED / "data").is_dir(), f"the beam data are not at {SHARED / 'data'}"
    work = tmp_path / "repo"
    work.mkdir()
    (tmp_path / "shared").symlink_to(SHARED, target_is_directory=True)
    monkeypatch.chdir(work)
    ns = {"__name__": "__readme__"}
    exec(compile(readme_loop(), "README.md (beam loop)", "exec"), ns)
    plt.close("all")

    r, m, s, data = ns["r"], ns["m"], ns["s"], ns["data"]
    level, gamma, sweep = data.curves[0]
    assert isinstance(r, nlsdof.FitResult) and r.converged
    # the files it writes
    for name in ("beam_fit.png", "beam.toml", "beam_fit.pkl"):
        assert (work / name).stat().st_size > 0, name
    assert (work / "beam_fit.png").read_bytes().startswith(b"\x89PNG")
    # the reloaded model is the fitted one: same model, gain and parameters
    assert m == r.model
    assert m.signal["input_gain"] == r.model.signal["input_gain"]
    # the prediction is the reloaded model's sweep at the measured level
    # (the fitted gain applied), bit for bit, and a resonance in the band
    again = m.sweep(gamma, np.linspace(120.0, 210.0, 901), sweep)
    np.testing.assert_array_equal(s.amplitude, again.amplitude)
    np.testing.assert_allclose(s.f_hz, np.linspace(120.0, 210.0, 901), rtol=1e-15)
    peak = s.f_hz[np.argmax(s.amplitude)]
    assert 130.0 < peak < 200.0, peak
    # predict() at the measured frequencies of that curve is the fit's own
    # model curve there: the DataFrame's model column, bit for bit
    curves = ns["curves"]
    own = curves[(curves.level == level) & (curves.sweep == sweep)]
    assert len(own) > 10
    at_data = r.predict(gamma, own.f_hz.to_numpy(), sweep)
    np.testing.assert_array_equal(at_data.amplitude, own.model_amplitude.to_numpy())
    # the pickle is the whole result
    with open(work / "beam_fit.pkl", "rb") as f:
        back = pickle.load(f)
    assert back == r and back.report() == r.report()
    # the block's relative data path is what was read
    assert os.path.samefile(
        work / "../shared/data/clamped-beam-duffing-catarinaluz/cc_beam_no_magnet_24C",
        SHARED / "data" / "clamped-beam-duffing-catarinaluz" / "cc_beam_no_magnet_24C",
    )
