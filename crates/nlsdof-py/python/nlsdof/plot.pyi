"""Type stubs of ``nlsdof.plot`` (matplotlib is an optional extra, so the
Axes are typed ``Any``)."""

from typing import Any, Mapping

from ._nlsdof import FitResult, Spectrogram

COLOURS: list[str]
GREY: str
DARK: str

def colour(i: int) -> str:
    """The `i`-th colour of the palette (20 distinct, cycling)."""

def sweep_style(sweep: str) -> dict[str, Any]:
    """matplotlib keywords of a sweep direction (up: solid, filled dots;
    down: dashed, hollow circles)."""

def length_unit(peak: float) -> tuple[str, float]:
    """The largest of m, mm, µm, nm in which `peak` (m) is at least 1, and
    its scale from metres."""

def fit(result: FitResult, ax: Any = None) -> Any:
    """The measured points and the fit's model curves per level and sweep;
    `ax=None` draws a new figure. Returns the Axes."""

def landscape(result: FitResult | Mapping[str, Any], ax: Any = None) -> Any:
    """The exponent landscape (map, or 1-D profile). Returns the Axes."""

def spectrogram(spec: Spectrogram, ax: Any = None, dynamic_range_db: float = 80.0) -> Any:
    """The STFT heat map in dB. Returns the Axes."""

def decay(
    result: Mapping[str, Any],
    x: Any = None,
    ax: Any = None,
    what: str = "envelope",
    column: str = "x",
    unit: str | None = None,
) -> Any:
    """A panel of the decay figure ("envelope", "backbone" or "damping").
    Returns the Axes."""

def fit_time(result: Mapping[str, Any], y: Any, ax: Any = None) -> Any:
    """Measured and model output per range of a time fit. Returns the Axes."""

def linear_id(result: Mapping[str, Any], ax: Any = None, what: str = "magnitude") -> Any:
    """A panel of the linear-identification figure ("magnitude", "phase" or
    "nyquist"). Returns the Axes."""
