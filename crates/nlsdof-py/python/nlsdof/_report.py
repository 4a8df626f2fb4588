"""Documents (the CLI's ``--json``) as dicts that Jupyter shows as tables.

`Report` is a ``dict`` (equal to the CLI's document, key for key) with a
``kind`` naming the call that made it and a ``_repr_html_``: the status
first (converged / adequate / warnings), then a table of the parameters
with their values, 95 % intervals where there are any, and SI units.
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable
from typing import Any

Row = tuple[str, Any, str, str]

# units of the mass-normalised parameters (the library's Parameter info)
UNITS = {
    "alpha": "1/s^2",
    "delta": "1/s",
    "beta": "1/(s^2 m^rho)",
    "rho": "-",
    "kappa": "s^(eta-1)/m^eta",
    "eta": "-",
    "gain": "-",
    "input_offset": "m/s^2",
    "output_offset": "m",
    "x0": "m",
    "v0": "m/s",
    "f_n_hz": "Hz",
    "zeta": "-",
    "mass": "kg",
    "stiffness": "N/m",
    "damping": "N s/m",
    "fs": "Hz",
    "fs_hz": "Hz",
    "resolution_hz": "Hz",
}


def _num(v: Any) -> str:
    if isinstance(v, bool) or v is None:
        return html.escape(str(v))
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "NaN"
        return f"{v:.6g}"
    return html.escape(str(v))


def _interval(lo: Any, hi: Any) -> str:
    if not isinstance(lo, (int, float)) or not isinstance(hi, (int, float)):
        return "&mdash;"
    return f"[{_num(lo)}, {_num(hi)}]"


def _table(rows: list[tuple[str, Any, str, str]]) -> str:
    h = (
        "<table><tr><th>parameter</th><th>value</th><th>95 % interval</th>"
        "<th>unit</th></tr>"
    )
    for name, value, interval, unit in rows:
        h += (
            f"<tr><td>{html.escape(name)}</td><td>{_num(value)}</td>"
            f"<td>{interval}</td><td>{html.escape(unit)}</td></tr>"
        )
    return h + "</table>"


def _status(doc: dict[str, Any]) -> str:
    parts = []
    if "converged" in doc:
        parts.append("converged" if doc["converged"] else "<b>not converged</b>")
    if "adequate" in doc:
        parts.append("adequate" if doc["adequate"] else "<b>not adequate</b>")
    warnings = doc.get("warnings") or ([doc["warning"]] if doc.get("warning") else [])
    s = ", ".join(parts)
    for w in warnings:
        s += f"<br><b>WARNING:</b> {html.escape(str(w))}"
    return s


def _rows_fit_time(doc: dict[str, Any]) -> list[tuple[str, Any, str, str]]:
    ci = {c["name"]: c for c in doc.get("intervals_95") or []}
    free = set(doc.get("free") or [])
    rows = []
    for name, value in (doc.get("parameters") or {}).items():
        if name not in free and name not in ci:
            continue
        c = ci.get(name)
        iv = _interval(c.get("lower"), c.get("upper")) if c else "&mdash;"
        rows.append((name, value, iv, UNITS.get(name, "")))
    return rows


def _rows_decay(doc: dict[str, Any]) -> list[tuple[str, Any, str, str]]:
    rows = []
    for part in ("stiffness_fit", "damping_fit"):
        for p in (doc.get(part) or {}).get("parameters") or []:
            label = f"{part.split('_')[0]}: {p['name']}"
            rows.append((label, p.get("value"), _interval(p.get("lower"), p.get("upper")), ""))
    return rows


def _rows_linear_id(doc: dict[str, Any]) -> list[tuple[str, Any, str, str]]:
    sdof = doc.get("sdof") or {}
    rows = [
        (k, sdof[k], "&mdash;", UNITS.get(k, ""))
        for k in ("alpha", "delta", "f_n_hz", "zeta", "mass", "stiffness", "damping")
        if sdof.get(k) is not None
    ]
    for method in ("half_power", "circle_fit"):
        m = doc.get(method) or {}
        for k in ("f_n_hz", "zeta"):
            if isinstance(m.get(k), (int, float)):
                rows.append((f"{method}: {k}", m[k], "&mdash;", UNITS[k]))
    return rows


def _rows_fit(doc: dict[str, Any]) -> list[tuple[str, Any, str, str]]:
    rows = []
    for p in doc.get("parameters") or []:
        if not isinstance(p, dict) or "name" not in p:
            continue
        ci = p.get("interval_95") or p.get("interval") or {}
        iv = _interval(ci.get("lower"), ci.get("upper")) if isinstance(ci, dict) else "&mdash;"
        rows.append((p["name"], p.get("value"), iv, p.get("unit") or UNITS.get(p["name"], "")))
    return rows


def _scalars(doc: dict[str, Any]) -> list[tuple[str, Any, str, str]]:
    return [
        (k, v, "&mdash;", UNITS.get(k, ""))
        for k, v in doc.items()
        if isinstance(v, (int, float, str)) and not isinstance(v, bool) and not k.endswith("_s")
    ]


class Report(dict[str, Any]):
    """A document (dict) of `kind` ("decay", "fit_time", "linear_id",
    "inspect", "frf_estimate", "compare") that Jupyter shows as a table.
    What ``nlsdof.decay``, ``fit_time``, ``linear_id``, ``inspect``,
    ``frf_estimate`` and ``compare`` return (typed so in the stubs)."""

    kind: str

    def __init__(self, doc: dict[str, Any], kind: str) -> None:
        super().__init__(doc)
        self.kind = kind

    def __reduce__(self) -> Any:
        return (Report, (dict(self), self.kind))

    def plot(self, *args: Any, **kwargs: Any) -> Any:
        """The CLI's figure of this document with matplotlib
        (``nlsdof.plot.decay``, ``fit_time`` or ``linear_id``, by `kind`;
        `args` as those take after the document, e.g. the record `x` of a
        decay or the output `y` of a time fit). Returns the Axes."""
        from . import plot

        figures: dict[str, Callable[..., Any]] = {
            "decay": plot.decay,
            "fit_time": plot.fit_time,
            "linear_id": plot.linear_id,
        }
        draw = figures.get(self.kind)
        if draw is None:
            raise ValueError(f"no figure for a {self.kind!r} document")
        return draw(self, *args, **kwargs)

    def _repr_html_(self) -> str:
        doc: dict[str, Any] = self
        title = f"nlsdof {html.escape(self.kind)}"
        if "model" in doc and isinstance(doc["model"], str):
            title += f": {html.escape(doc['model'])}"
        h = f"<div><b>{title}</b>"
        status = _status(doc)
        if status:
            h += f" &mdash; {status}"
        if self.kind == "compare":
            h += (
                "<table><tr><th>model</th><th>cost</th><th>converged</th>"
                "<th>adequate</th></tr>"
            )
            for m in doc.get("models") or []:
                adequate = (m.get("adequacy") or {}).get("adequate", m.get("adequate"))
                h += (
                    f"<tr><td>{html.escape(str(m.get('model')))}</td>"
                    f"<td>{_num(m.get('cost'))}</td><td>{_num(m.get('converged'))}</td>"
                    f"<td>{_num(adequate)}</td></tr>"
                )
            return h + "</table></div>"
        by_kind: dict[str, Callable[[dict[str, Any]], list[Row]]] = {
            "fit_time": _rows_fit_time,
            "decay": _rows_decay,
            "linear_id": _rows_linear_id,
        }
        rows = by_kind.get(self.kind, _rows_fit)(doc)
        if not rows:
            rows = _scalars(doc)
        if "headline" in doc:
            h += f"<br>{html.escape(str(doc['headline']))}"
        return h + _table(rows) + "</div>"
