"""The examples in the docstrings of the module nlsdof (the functions and
classes of ``nlsdof.__all__`` and their public methods, the extension's
docstrings included), run by doctest from the repository root so that
their paths (examples/, ../shared/data/) resolve.

Each docstring is one test; the entry points of ``nlsdof.__init__`` that
must carry an example are listed in ``REQUIRED``.
"""

import doctest
import inspect
import pathlib
import time

import pytest

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]
SHARED = ROOT.parent / "shared" / "data"

# functions whose docstrings must hold a runnable example
REQUIRED = [
    "g",
    "Model",
    "fit",
    "read_stepped_sine",
    "read_beam_dir",
    "linear_id",
    "spectrogram",
    "compare_spectrograms",
    "decay",
    "fit_time",
    "read_lvm",
    "read_polytec",
    "read_polytec_sweep",
    "read_mat",
    "frf_estimate",
    "compare",
    "signal",
]


def docstrings():
    """(name, docstring) of every public object of nlsdof and its methods."""
    seen = set()
    for name in sorted(nlsdof.__all__):
        obj = getattr(nlsdof, name)
        if not (callable(obj) or inspect.isclass(obj)):
            continue
        items = [(name, obj)]
        if inspect.isclass(obj):
            for m, v in sorted(vars(obj).items()):
                if not m.startswith("_") or m in ("__new__", "__init__"):
                    items.append((f"{name}.{m}", v))
        for qual, v in items:
            doc = getattr(v, "__doc__", None)
            if isinstance(doc, str) and ">>>" in doc and id(doc) not in seen:
                seen.add(id(doc))
                yield qual, doc


DOCS = dict(docstrings())


def test_required_entry_points_have_examples():
    missing = [n for n in REQUIRED if n not in DOCS]
    assert not missing, f"no >>> example in the docstring of {missing}"


@pytest.mark.parametrize("name", sorted(DOCS))
def test_docstring_example(name, monkeypatch):
    if "../shared/data" in DOCS[name] and not SHARED.exists():
        pytest.skip("../shared/data is not beside the repository")
    monkeypatch.chdir(ROOT)
    parser = doctest.DocTestParser()
    test = parser.get_doctest(DOCS[name], {}, f"nlsdof.{name}", None, 0)
    runner = doctest.DocTestRunner(
        optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    )
    out = []
    t0 = time.perf_counter()
    runner.run(test, out=out.append)
    elapsed = time.perf_counter() - t0
    assert runner.failures == 0, "".join(out)
    # examples stay quick (generous: the CI machine may be loaded)
    assert elapsed < 10.0, f"{name}: example took {elapsed:.1f} s"
