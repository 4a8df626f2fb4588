"""Type stubs of ``nlsdof.plot`` (matplotlib is an optional extra, so the
Axes are typed ``Any``)."""

from typing import Any

from ._nlsdof import FitResult

def fit(result: FitResult, ax: Any = None) -> Any:
    """The measured points and the fit's model curves per level and sweep;
    `ax=None` draws a new figure. Returns the Axes."""
