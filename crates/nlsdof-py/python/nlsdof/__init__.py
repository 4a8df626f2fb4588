"""nlsdof: identify and simulate nonlinear single-degree-of-freedom power-law
models of vibrating structures (Rust core).

    m x'' + c x' + k x + c_e x'|x'|^eta + k_r x|x|^rho = m gamma(t)

SI units throughout; input levels gamma (m/s^2) and amplitudes (m) are
zero-to-peak; frequencies are in Hz. Equation numbers refer to Civera et al.
(2021), "Generalised power-law stiffness and damping for nonlinear
reduced-order models".

Entry points: ``g``, ``Model`` (steady_states, sweep, simulate,
stepped_sine, harmonic_sweep, hb_error), ``fit`` with ``read_stepped_sine``/``read_beam_dir``,
``linear_id``, ``spectrogram``, ``compare_spectrograms``, ``decay``,
``fit_time``; readers ``read_lvm``, ``read_polytec``, ``read_polytec_sweep``,
``read_mat``, ``read_uff``; the verbs ``frf_estimate``, ``compare`` and
``signal``. Their docstrings carry runnable examples. Every error of the
library is a ``ValueError`` with the same one-line message as the CLI.
"""

from ._nlsdof import (
    FitResult,
    HarmonicSweep,
    Jump,
    Model,
    RigSweep,
    Simulation,
    SteadyState,
    SteppedSineData,
    Spectrogram,
    Sweep,
    __version__,
    compare,
    compare_spectrograms,
    decay,
    fit,
    fit_time,
    frf_estimate,
    g,
    inspect,
    linear_id,
    read_beam_dir,
    read_lvm,
    read_mat,
    read_polytec,
    read_polytec_sweep,
    read_stepped_sine,
    read_uff,
    signal,
    spectrogram,
    write_uff,
)

__all__ = [
    "FitResult",
    "HarmonicSweep",
    "Jump",
    "Model",
    "RigSweep",
    "Simulation",
    "SteadyState",
    "SteppedSineData",
    "Spectrogram",
    "Sweep",
    "__version__",
    "compare",
    "compare_spectrograms",
    "decay",
    "fit",
    "fit_time",
    "frf_estimate",
    "g",
    "inspect",
    "linear_id",
    "read_beam_dir",
    "read_lvm",
    "read_mat",
    "read_polytec",
    "read_polytec_sweep",
    "read_stepped_sine",
    "read_uff",
    "signal",
    "spectrogram",
    "write_uff",
]
