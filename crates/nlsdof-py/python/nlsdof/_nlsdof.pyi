"""Type stubs of the extension module ``nlsdof._nlsdof`` (re-exported by
``nlsdof``). Kept by hand from ``crates/nlsdof-py/src/*.rs``; checked against
the built module by ``mypy.stubtest`` in ``tests/test_typing.py``.

Conventions: arguments read as numpy arrays accept anything
``numpy.asarray(x, dtype=float64)`` accepts (``ArrayLike``); option strings
are typed ``str`` (they are case-insensitive at run time, so a ``Literal``
would reject valid calls); the JSON-like documents of the CLI's ``--json``
are ``dict[str, Any]``, or ``nlsdof._report.Report`` (a ``dict[str, Any]``
with ``plot()`` and ``_repr_html_``) where the call returns one: ``decay``,
``fit_time``, ``linear_id``, ``inspect``, ``frf_estimate``, ``compare``. pandas and matplotlib are optional extras, so
DataFrames and Axes are ``Any``.
"""

import os
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from typing import Any, ClassVar, Protocol, final, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._report import Report

__all__ = [
    "g",
    "Model",
    "SteadyState",
    "Jump",
    "Sweep",
    "HarmonicSweep",
    "RigSweep",
    "Simulation",
    "SteppedSineData",
    "FitResult",
    "read_stepped_sine",
    "read_beam_dir",
    "fit",
    "Spectrogram",
    "linear_id",
    "spectrogram",
    "compare_spectrograms",
    "decay",
    "fit_time",
    "inspect",
    "read_uff",
    "write_uff",
    "read_lvm",
    "read_polytec",
    "read_polytec_sweep",
    "read_mat",
    "frf_estimate",
    "compare",
    "signal",
    "__version__",
]

__version__: str

_Path = str | os.PathLike[str]
# a level (m/s^2): a Python or numpy scalar
_Scalar = float | np.floating[Any] | np.integer[Any]

class _Columns(Protocol):
    """A mapping of columns by name: a dict, a pandas DataFrame, ..."""

    def __contains__(self, key: Any, /) -> bool: ...
    def __getitem__(self, key: str, /) -> Any: ...

# what `fit` and `inspect` take as data (a str is read as a CSV path)
_Data = SteppedSineData | _Path | _Columns
# `progress=` of the long calls: None (quiet), True (a tqdm bar, plain lines
# on stderr without tqdm) or a callable progress(stage, done, total)
_Progress = bool | Callable[[str, int, int], object] | None

def g(mu: float) -> float:
    """The shape factor of the equivalent coefficients (paper Eq 12/24):
    `g(mu) = 2 Gamma((3+mu)/2) / (sqrt(pi) Gamma(2+mu/2))`, for `mu > -3`."""

@final
class Model:
    """A power-law SDoF model (SI units):

        m x'' + c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho = m gamma(t)

    `Model(mass, stiffness, damping, nonlinear_stiffness=(k_r, rho),
    nonlinear_damping=(c_e, eta), signal=None)`; levels gamma in m/s^2 and
    amplitudes in m, both zero-to-peak; frequencies in Hz. Models pickle,
    deep-copy and compare by value."""

    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __new__(
        cls,
        mass: float,
        stiffness: float,
        damping: float,
        nonlinear_stiffness: Sequence[float] | NDArray[Any] | None = None,
        nonlinear_damping: Sequence[float] | NDArray[Any] | None = None,
        signal: dict[str, Any] | None = None,
    ) -> Model: ...
    @staticmethod
    def from_toml(path: _Path) -> Model:
        """Reads a model file (TOML, SI units) with its `[signal]` and
        `[provenance]` tables."""
    @staticmethod
    def from_toml_str(text: str) -> Model:
        """Parses model-file text (as `to_toml()` writes it)."""
    def to_toml(self) -> str:
        """The model file (TOML) of this model."""
    def __reduce__(self) -> tuple[Callable[[str], Model], tuple[str]]: ...
    def __eq__(self, other: object, /) -> bool: ...
    @property
    def signal(self) -> dict[str, Any] | None:
        """The `[signal]` table (`input_gain`, `input_offset`,
        `output_offset`; `input_interpolation`, `substeps` where stated), or
        None."""
    @property
    def input_gain(self) -> float:
        """The input gain applied to every level and input (1 without a
        `[signal]` table)."""
    @property
    def provenance(self) -> dict[str, Any] | None:
        """The `[provenance]` table as a dict, or None."""
    @property
    def mass(self) -> float:
        """Mass m, kg."""
    @property
    def stiffness(self) -> float:
        """Linear stiffness k, N/m."""
    @property
    def damping(self) -> float:
        """Linear damping c, N s/m."""
    @property
    def nonlinear_stiffness(self) -> tuple[float, float] | None:
        """(k_r, rho) or None."""
    @property
    def nonlinear_damping(self) -> tuple[float, float] | None:
        """(c_e, eta) or None."""
    @property
    def f_n_hz(self) -> float:
        """Linear natural frequency sqrt(k/m) / (2 pi), Hz."""
    @property
    def zeta(self) -> float:
        """Linear damping ratio c / (2 m omega_n)."""
    def steady_states(
        self, gamma: float, f_hz: float, formulation: str = "hb"
    ) -> list[SteadyState]:
        """Every steady state at level `gamma` (m/s^2) and frequency `f_hz`
        (Hz), ordered by amplitude; `formulation` "hb" or "modulation"."""
    # one level gives one Sweep, a list of levels one Sweep per level; a
    # numpy array gives a list, except a 0-d array (one Sweep)
    @overload
    def sweep(
        self,
        gamma: _Scalar,
        f_hz: ArrayLike,
        direction: str = "up",
        formulation: str = "hb",
    ) -> Sweep:
        """A stepped-sine sweep at level `gamma` (m/s^2) over `f_hz` (Hz),
        `direction` "up" or "down"; with a sequence of levels, one `Sweep`
        per level."""
    @overload
    def sweep(
        self,
        gamma: Sequence[float],
        f_hz: ArrayLike,
        direction: str = "up",
        formulation: str = "hb",
    ) -> list[Sweep]: ...
    @overload
    def sweep(
        self,
        gamma: ArrayLike,
        f_hz: ArrayLike,
        direction: str = "up",
        formulation: str = "hb",
    ) -> Sweep | list[Sweep]: ...
    @overload
    def harmonic_sweep(
        self, gamma: _Scalar, f_hz: ArrayLike, harmonics: int, direction: str = "up"
    ) -> HarmonicSweep:
        """Multi-harmonic balance with `harmonics` harmonics (as `nlsdof frf
        --harmonics H`); with a sequence of levels, one `HarmonicSweep` per
        level."""
    @overload
    def harmonic_sweep(
        self,
        gamma: Sequence[float],
        f_hz: ArrayLike,
        harmonics: int,
        direction: str = "up",
    ) -> list[HarmonicSweep]: ...
    @overload
    def harmonic_sweep(
        self, gamma: ArrayLike, f_hz: ArrayLike, harmonics: int, direction: str = "up"
    ) -> HarmonicSweep | list[HarmonicSweep]: ...
    def hb_error(
        self,
        gamma: float,
        f_min: float | None = None,
        f_max: float | None = None,
        tol: float = 1e-6,
        h_max: int = 63,
    ) -> dict[str, Any]:
        """How wrong the first-order balance is (`nlsdof hb-error --json`,
        the level's entry)."""
    def simulate(
        self,
        u: ArrayLike,
        fs: float,
        method: str = "rk4",
        base: bool = False,
        x0: float = 0.0,
        v0: float = 0.0,
        samples_per_step: int | None = None,
        rtol: float = 1e-10,
        atol: float = 1e-13,
        check: bool = True,
    ) -> Simulation:
        """Simulates Eq 32 driven by `u` (m/s^2) sampled at `fs` Hz; unpacks
        as `x, v` (m, m/s)."""
    def stepped_sine(
        self,
        gamma: float,
        f_hz: ArrayLike,
        direction: str = "up",
        samples_per_cycle: int = 64,
        tolerance: float = 1e-4,
        max_cycles: int = 5000,
    ) -> RigSweep:
        """The virtual stepped-sine rig at level `gamma` (m/s^2) over `f_hz`
        (Hz), as `nlsdof stepped-sine`."""

@final
class SteadyState:
    """One steady state: amplitude (m, zero-to-peak), phase lag (deg),
    stability."""

    @property
    def amplitude(self) -> float: ...
    @property
    def phase_deg(self) -> float: ...
    @property
    def stable(self) -> bool: ...

@final
class Jump:
    """A jump of a sweep: frequency (Hz) and the amplitudes (m) before and
    after."""

    @property
    def f_hz(self) -> float: ...
    @property
    def amplitude_before(self) -> float: ...
    @property
    def amplitude_after(self) -> float: ...

@final
class Sweep:
    """A stepped-sine sweep of the first-order balance."""

    @property
    def gamma(self) -> float:
        """Input level, m/s^2 zero-to-peak."""
    @property
    def f_hz(self) -> NDArray[np.float64]:
        """Frequencies, Hz."""
    @property
    def amplitude(self) -> NDArray[np.float64]:
        """Amplitudes followed by the sweep, m zero-to-peak (NaN:
        unbounded)."""
    @property
    def phase_deg(self) -> NDArray[np.float64]:
        """Phase lag of x behind the input, deg (NaN: no motion or
        unbounded)."""
    @property
    def stable(self) -> NDArray[np.bool_]:
        """Whether the followed state is stable."""
    @property
    def jumps(self) -> list[Jump]: ...
    @property
    def folds_hz(self) -> list[float]:
        """Fold (limit-point) frequencies in the band, Hz."""
    @property
    def phase_quadrature(self) -> tuple[float, float] | None:
        """The phase-quadrature (90 deg) point `(f_hz, amplitude)`, or
        None."""
    def to_dict(self) -> dict[str, Any]:
        """The level's entry of `nlsdof frf --json`."""
    def __len__(self) -> int: ...

@final
class RigSweep:
    """A run of the virtual stepped-sine rig."""

    @property
    def gamma(self) -> float: ...
    @property
    def f_hz(self) -> NDArray[np.float64]: ...
    @property
    def amplitude(self) -> NDArray[np.float64]: ...
    @property
    def phase_deg(self) -> NDArray[np.float64]: ...
    @property
    def settled(self) -> NDArray[np.bool_]: ...
    @property
    def cycles(self) -> NDArray[np.uint64]: ...
    @property
    def integration_error(self) -> float: ...
    @property
    def simulated_s(self) -> float: ...

@final
class HarmonicSweep:
    """A multi-harmonic sweep."""

    @property
    def gamma(self) -> float: ...
    @property
    def harmonics(self) -> int: ...
    @property
    def f_hz(self) -> NDArray[np.float64]: ...
    @property
    def amplitude(self) -> NDArray[np.float64]: ...
    @property
    def phase_deg(self) -> NDArray[np.float64]: ...
    @property
    def stable(self) -> NDArray[np.bool_]: ...
    @property
    def max_abs_x(self) -> NDArray[np.float64]: ...
    @property
    def harmonic_amplitudes(self) -> NDArray[np.float64]:
        """Amplitudes of the harmonics 0..H at every point, m: shape
        (points, H+1)."""
    @property
    def jumps(self) -> list[Jump]: ...
    @property
    def folds_hz(self) -> list[float]: ...
    @property
    def warning(self) -> str | None: ...
    def to_dict(self) -> dict[str, Any]: ...
    def __len__(self) -> int: ...

@final
class Simulation:
    """The result of `Model.simulate`; unpacks as `x, v`."""

    @property
    def x(self) -> NDArray[np.float64]: ...
    @property
    def v(self) -> NDArray[np.float64]: ...
    @property
    def integration_error(self) -> float | None: ...
    @property
    def warning(self) -> str | None: ...
    def _repr_html_(self) -> str: ...
    def __len__(self) -> int: ...
    def __getitem__(self, i: int, /) -> NDArray[np.float64]: ...
    def __iter__(self) -> Iterator[NDArray[np.float64]]: ...

@final
class SteppedSineData:
    """Stepped-sine amplitude curves at several levels (m, m/s^2, Hz,
    deg)."""

    __hash__: ClassVar[None]  # type: ignore[assignment]
    def __new__(cls, columns: _Data) -> SteppedSineData: ...
    @property
    def level(self) -> list[str]: ...
    @property
    def gamma(self) -> NDArray[np.float64]: ...
    @property
    def f_hz(self) -> NDArray[np.float64]: ...
    @property
    def amplitude(self) -> NDArray[np.float64]: ...
    @property
    def phase_deg(self) -> NDArray[np.float64]: ...
    @property
    def sweep(self) -> list[str]: ...
    @property
    def weight(self) -> NDArray[np.float64]: ...
    @property
    def source(self) -> str | None: ...
    @property
    def curves(self) -> list[tuple[str, float, str]]:
        """`(level, gamma, sweep)` of every curve, in data order."""
    def to_dict(self) -> dict[str, Any]: ...
    def select(
        self, level: str | None = None, sweep: str | None = None
    ) -> SteppedSineData: ...
    def __getitem__(self, key: str | tuple[str, str], /) -> SteppedSineData: ...
    def to_dataframe(self) -> Any:
        """A pandas DataFrame (needs pandas)."""
    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]: ...
    @staticmethod
    def _from_state(
        curves: list[
            tuple[str, float, str, list[float], list[float], list[float] | None, list[float]]
        ],
        source: str | None,
    ) -> SteppedSineData: ...
    def __eq__(self, other: object, /) -> bool: ...
    def __len__(self) -> int: ...

@final
class FitResult:
    """The outcome of `fit`."""

    __hash__: ClassVar[None]  # type: ignore[assignment]
    @property
    def parameters(self) -> dict[str, dict[str, Any]]:
        """name -> {"value", "interval" ((lo, hi) or None), "unit",
        "status", "physical" {"name", "value", "unit"}}."""
    @property
    def cost(self) -> float: ...
    @property
    def converged(self) -> bool: ...
    @property
    def warning(self) -> str | None: ...
    @property
    def notes(self) -> list[str]:
        """Results that are not warnings, e.g. "eta = -1 (Coulomb friction)"."""
    @property
    def adequate(self) -> bool: ...
    @property
    def minima(self) -> list[dict[str, Any]]: ...
    @property
    def model(self) -> Model: ...
    def to_dict(self) -> dict[str, Any]: ...
    def to_toml(self) -> str: ...
    def profile(
        self,
        parameter: str = "rho",
        step: float | None = None,
        max_steps: int = 24,
        *,
        progress: _Progress = None,
    ) -> dict[str, Any]: ...
    def report(self, intervals: str | None = None) -> str: ...
    def fitted_curves(self) -> dict[str, Any]: ...
    def plot(self, ax: Any = None) -> Any:
        """matplotlib: returns the Axes (needs matplotlib)."""
    def landscape(self) -> dict[str, Any]:
        """The exponent landscape document (rho, eta, cost, minima, fitted)."""
    def plot_landscape(self, ax: Any = None) -> Any:
        """matplotlib map (or 1-D profile) of the landscape: returns the Axes."""
    def to_dataframe(self) -> Any:
        """A pandas DataFrame (needs pandas)."""
    @overload
    def predict(self, gamma: _Scalar, f_hz: ArrayLike, direction: str = "up") -> Sweep: ...
    @overload
    def predict(
        self, gamma: Sequence[float], f_hz: ArrayLike, direction: str = "up"
    ) -> list[Sweep]: ...
    @overload
    def predict(
        self, gamma: ArrayLike, f_hz: ArrayLike, direction: str = "up"
    ) -> Sweep | list[Sweep]: ...
    def __reduce__(self) -> tuple[Callable[[bytes], FitResult], tuple[bytes]]: ...
    @staticmethod
    def _from_state(state: bytes) -> FitResult: ...
    def __eq__(self, other: object, /) -> bool: ...
    def _repr_html_(self) -> str: ...

def read_stepped_sine(
    path: _Path,
    velocity: bool = False,
    acceleration: bool = False,
    gamma_in_g: bool = False,
    peak_to_peak: bool = False,
) -> SteppedSineData: ...
def read_beam_dir(path: _Path, runs: str = "up") -> SteppedSineData: ...
def fit(
    data: _Data,
    model: str = "generalised",
    *,
    mass: float | None = None,
    fix: dict[str, float] | None = None,
    free: Sequence[str] | None = None,
    bounds: dict[str, tuple[float, float]] | dict[str, Sequence[float]] | None = None,
    sign: str = "data",
    phase: str | tuple[str, float] | tuple[str, float, float] | None = None,
    phase_weight: float | None = None,
    weighting: str = "absolute",
    jump_weight: float | None = None,
    jump_reading: str = "auto",
    integer: bool = False,
    grid: Sequence[int] | None = None,
    refine: int | None = None,
    starts: int = 1,
    seed: int = 1,
    intervals: str = "one",
    progress: _Progress = None,
    from_inspect: bool = False,
) -> FitResult: ...

@final
class Spectrogram:
    """An STFT spectrogram: `times` (s), `frequencies` (Hz), `magnitude` of
    shape (len(times), len(frequencies))."""

    @property
    def times(self) -> NDArray[np.float64]: ...
    @property
    def frequencies(self) -> NDArray[np.float64]: ...
    @property
    def magnitude(self) -> NDArray[np.float64]: ...
    def plot(self, ax: Any = None) -> Any:
        """matplotlib heat map in dB: returns the Axes (needs matplotlib)."""
    def _repr_html_(self) -> str: ...

def linear_id(
    f_hz: ArrayLike,
    frf: ArrayLike,
    input: str = "acceleration",
    output: str = "displacement",
    mass: float | None = None,
    poles: int | str | None = None,
    max_poles: int = 20,
    f_min: float | None = None,
    f_max: float | None = None,
    mode: int | None = None,
    constant: bool = True,
    proportional: bool = False,
    weight: str = "uniform",
    max_iterations: int = 30,
) -> Report: ...
def spectrogram(
    x: ArrayLike,
    fs: float,
    segments: int = 15,
    overlap: float = 0.5,
    window: str = "hamming",
    periodic: bool = False,
    nfft: int | None = None,
    detrend: str = "none",
    scaling: str = "amplitude",
    f_min: float | None = None,
    f_max: float | None = None,
) -> Spectrogram: ...
def compare_spectrograms(
    measured: ArrayLike,
    model: ArrayLike,
    fs: float,
    segments: int = 15,
    overlap: float = 0.5,
    window: str = "hamming",
    periodic: bool = False,
    nfft: int | None = None,
    detrend: str = "none",
    scaling: str = "amplitude",
    f_min: float | None = None,
    f_max: float | None = None,
    floor: float = 0.01,
) -> dict[str, Any]: ...
def decay(
    x: ArrayLike,
    fs: float,
    t_start: float | None = None,
    band: Sequence[float] | None = None,
    bins: int = 30,
) -> Report: ...
def fit_time(
    u: ArrayLike,
    y: ArrayLike,
    fs: float,
    model: str = "duffing",
    fit_range: Sequence[int] | None = None,
    tests: Sequence[Sequence[int]] | None = None,
    starts: int = 1,
    seed: int = 1,
    max_iterations: int = 400,
    input_interpolation: str = "cubic",
    substeps: int | None = None,
    progress: _Progress = None,
    fix: Mapping[str, float] | None = None,
) -> Report: ...
def inspect(data: _Data, phase: str = "auto", min_jump_ratio: float = 1.2) -> Report: ...
def read_uff(
    path: _Path, dataset: int | str | None = None, headers_only: bool = False
) -> list[dict[str, Any]]: ...
def write_uff(
    path: _Path,
    datasets: dict[str, Any] | Iterable[dict[str, Any]],
    binary: bool = False,
) -> None: ...
def read_lvm(path: _Path, columns: Sequence[str] | None = None) -> dict[str, NDArray[np.float64]]:
    """The columns of a LabVIEW `.lvm` (or any delimited text table) by name."""

def read_polytec(path: _Path) -> dict[str, NDArray[np.float64]]:
    """A Polytec ASCII time export: `t` (s) and the channel by its `Signal:` name."""

def read_polytec_sweep(path: _Path) -> list[dict[str, NDArray[np.float64]]]:
    """The runs of a Polytec swept-sine FRF export: `f_hz`, `amplitude`, `phase_deg`."""

def read_mat(path: _Path, variables: Sequence[str] | None = None) -> dict[str, NDArray[np.float64]]:
    """The real numeric arrays of a MAT v5 file, by variable name, in MATLAB shape."""

def frf_estimate(
    input: _Path | ArrayLike,
    output: _Path | ArrayLike | None = None,
    *,
    fs: float | None = None,
    input_channel: str = "1",
    output_channel: str | None = None,
    method: str = "h1",
    segment: int | None = None,
    overlap: float = 0.5,
    window: str = "hann",
    symmetric_window: bool = False,
    f_min: float | None = None,
    f_max: float | None = None,
    out: _Path | None = None,
) -> Report:
    """`nlsdof frf-estimate --json`, plus `f_hz`, `frf` and `coherence` arrays."""

def compare(
    data: _Data,
    models: str | Sequence[str] | None = None,
    *,
    free: str | Sequence[str] | None = None,
    starts: int | None = None,
    seed: int = 1,
    mass: float | None = None,
    sign: str = "data",
    progress: Any = None,
) -> Report:
    """`nlsdof compare --json`: `{"models": [document, ...]}`."""

def signal(
    kind: str,
    *,
    amplitude: float,
    fs: float,
    freq: float | None = None,
    duration: float | None = None,
    phase_deg: float = 0.0,
    chirp_kind: str = "linear",
    f0: float | None = None,
    f1: float | None = None,
    rate: float | None = None,
    f_min: float | None = None,
    f_max: float | None = None,
    steps: int | None = None,
    sweep: str = "up",
    dwell_cycles: int | None = None,
    dwell: float | None = None,
    out: _Path | None = None,
) -> dict[str, NDArray[np.float64]]:
    """`nlsdof signal KIND`: `{"t": ..., "accel": ...}` (s, m/s^2)."""
