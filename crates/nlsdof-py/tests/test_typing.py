"""The type stubs (python/nlsdof/_nlsdof.pyi, plot.pyi, py.typed): shipped
with the installed package, consistent with the extension module
(mypy.stubtest), and good enough to type-check the examples in
examples/python and the README's Python blocks with mypy.

Needs mypy (``pip install mypy``, as .ci/run does); skipped without it.
"""

import pathlib
import re
import subprocess
import sys
import textwrap

import pytest

try:
    import mypy  # noqa: F401
except ImportError:  # pragma: no cover - depends on the environment
    pytest.skip(
        "mypy is not installed (pip install mypy): the stubs are not checked",
        allow_module_level=True,
    )

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]

# --strict, less what a script without annotations cannot meet (its own
# functions unannotated, untyped dask calls, `cols = {"level": [], ...}`):
# every body is still checked (--check-untyped-defs is part of --strict).
MYPY_FLAGS = [
    "--strict",
    "--allow-untyped-defs",
    "--allow-incomplete-defs",
    "--allow-untyped-calls",
    "--disable-error-code=var-annotated",
    "--no-error-summary",
    "--show-error-codes",
]

# Types the stubs must give (assert_type) and misuse they must catch: with
# --warn-unused-ignores (part of --strict), an ignore that is not needed is
# an error, so each `# type: ignore[code]` below asserts that mypy reports
# that error there.
PROBE = '''
from typing import Any

import numpy as np
from numpy.typing import NDArray
from typing_extensions import assert_type

import nlsdof
import nlsdof.plot
from nlsdof._report import Report

m = nlsdof.Model(1.0, 100.0, 0.5, nonlinear_stiffness=(1e3, 3.0))
assert_type(m, nlsdof.Model)
assert_type(nlsdof.Model.from_toml("m.toml"), nlsdof.Model)
assert_type(m.signal, dict[str, Any] | None)
assert_type(m.nonlinear_damping, tuple[float, float] | None)
assert_type(m.sweep(1.0, [1.0, 2.0]), nlsdof.Sweep)
assert_type(m.sweep(np.float64(1.0), np.linspace(1, 2, 3)), nlsdof.Sweep)
assert_type(m.sweep([1.0, 2.0], [1.0, 2.0]), list[nlsdof.Sweep])
assert_type(m.sweep(np.array([1.0, 2.0]), [1.0, 2.0]), nlsdof.Sweep | list[nlsdof.Sweep])
s = m.sweep(1.0, [1.0, 2.0])
assert_type(s.amplitude, NDArray[np.float64])
assert_type(s.stable, NDArray[np.bool_])
assert_type(s.jumps, list[nlsdof.Jump])
assert_type(s.phase_quadrature, tuple[float, float] | None)
assert_type(m.harmonic_sweep(1.0, [1.0, 2.0], 3), nlsdof.HarmonicSweep)
assert_type(m.steady_states(1.0, 1.5), list[nlsdof.SteadyState])
assert_type(m.stepped_sine(1.0, [1.0, 2.0]).cycles, NDArray[np.uint64])
sim = m.simulate(np.zeros(8), fs=10.0)
x, v = sim
assert_type(x, NDArray[np.float64])
assert_type(sim.integration_error, float | None)
data = nlsdof.read_beam_dir("beam")
assert_type(data["0.04g", "up"], nlsdof.SteppedSineData)
assert_type(data.curves, list[tuple[str, float, str]])
r = nlsdof.fit({"level": ["1"], "gamma": [1.0], "f_hz": [1.0], "amplitude": [1.0]}, mass=1.0)
r = nlsdof.fit(data, "duffing", fix={"alpha": 1.0}, bounds={"rho": (1.0, 5.0)}, phase=("lag", 0.0))
assert_type(r, nlsdof.FitResult)
assert_type(r.parameters, dict[str, dict[str, Any]])
assert_type(r.warning, str | None)
assert_type(r.model, nlsdof.Model)
assert_type(r.predict([1.0, 2.0], [1.0, 2.0]), list[nlsdof.Sweep])
assert_type(nlsdof.plot.fit(r), Any)
assert_type(nlsdof.spectrogram(np.zeros(64), fs=8.0).magnitude, NDArray[np.float64])
assert_type(nlsdof.fit_time(np.zeros(8), np.zeros(8), 8.0), Report)
# the documents with a figure are Reports: a dict with plot() (issue 27)
d = nlsdof.decay(np.zeros(8), 8.0)
assert_type(d, Report)
assert_type(d.plot(np.zeros(8)), Any)
assert_type(d["adequate"], Any)
doc: dict[str, Any] = d
assert_type(nlsdof.fit_time(np.zeros(8), np.zeros(8), 8.0).plot(np.zeros(8)), Any)
assert_type(nlsdof.linear_id([1.0, 2.0], [1.0, 2.0]), Report)
assert_type(nlsdof.linear_id([1.0, 2.0], [1.0, 2.0]).plot(what="phase"), Any)
assert_type(nlsdof.inspect(data), Report)
assert_type(nlsdof.compare_spectrograms(np.zeros(8), np.zeros(8), 8.0), dict[str, Any])
assert_type(nlsdof.read_uff("a.uff"), list[dict[str, Any]])
assert_type(nlsdof.read_lvm("a.lvm", columns=["X_Value"]), dict[str, NDArray[np.float64]])
assert_type(nlsdof.read_mat("a.mat"), dict[str, NDArray[np.float64]])
assert_type(nlsdof.read_polytec_sweep("f.txt"), list[dict[str, NDArray[np.float64]]])
assert_type(nlsdof.frf_estimate(np.zeros(8), np.zeros(8), fs=8.0), Report)
assert_type(nlsdof.compare(data, models=["linear", "duffing"]), Report)
assert_type(nlsdof.signal("sine", amplitude=1.0, fs=8.0, freq=1.0, duration=1.0)["t"], NDArray[np.float64])
assert_type(nlsdof.g(2.0), float)
assert_type(nlsdof.__version__, str)

nlsdof.g("2")  # type: ignore[arg-type]
m.sweep(1.0, [1.0], direction=1)  # type: ignore[call-overload]
nlsdof.fit(data, mass="1")  # type: ignore[arg-type]
m.mass = 2.0  # type: ignore[misc]
r.cost_function  # type: ignore[attr-defined]
nlsdof.read_uff("a.uff", dataset=1.5)  # type: ignore[arg-type]
d.plott()  # type: ignore[attr-defined]
'''


def readme_blocks():
    """The README's ```python blocks."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def mypy(args, cwd):
    # run outside the source tree, so that the installed package (and its
    # stubs) is what mypy reads
    return subprocess.run(
        [sys.executable, "-m", "mypy", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_stubs_and_marker_are_installed():
    pkg = pathlib.Path(nlsdof.__file__).parent
    for name in ("py.typed", "_nlsdof.pyi", "plot.pyi"):
        assert (pkg / name).is_file(), f"{name} is not installed next to {nlsdof.__file__}"


def test_examples_readme_and_probe_typecheck(tmp_path):
    examples = sorted((ROOT / "examples" / "python").glob("*.py"))
    assert examples, "no examples in examples/python"
    files = [str(p) for p in examples]
    blocks = readme_blocks()
    assert blocks, "README.md has no ```python block"
    for i, b in enumerate(blocks):
        p = tmp_path / f"readme_block_{i}.py"
        p.write_text(b, encoding="utf-8")
        files.append(str(p))
    probe = tmp_path / "stub_probe.py"
    probe.write_text(textwrap.dedent(PROBE), encoding="utf-8")
    files.append(str(probe))
    # the optional extras the examples import may be absent (nlsdof itself
    # must be found: the probe's assert_type fails if it reads as Any)
    config = tmp_path / "mypy.ini"
    config.write_text(
        "[mypy]\n[mypy-dask.*,distributed.*,matplotlib.*,pandas.*]\n"
        "ignore_missing_imports = True\n",
        encoding="utf-8",
    )
    r = mypy(
        [*MYPY_FLAGS, f"--config-file={config}", f"--cache-dir={tmp_path / 'cache'}", *files],
        tmp_path,
    )
    assert r.returncode == 0, f"mypy found errors:\n{r.stdout}{r.stderr}"


def test_stubtest(tmp_path):
    """The stubs agree with the built module: every public name, signature
    (names, defaults, keyword-only), class and property (mypy.stubtest; it
    cannot see the types a Rust function returns, which the probe above and
    the tests of the values cover)."""
    r = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "--concise", "nlsdof"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, f"stubtest found differences:\n{r.stdout}{r.stderr}"
