"""nlsdof.inspect: the document of `nlsdof inspect --json` (issue 29)."""

import json
import os
import pathlib
import subprocess

import pytest

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]
BEAM_24C = ROOT.parent / "shared" / "data" / "clamped-beam-duffing-catarinaluz" / "cc_beam_no_magnet_24C"


def cli():
    exe = pathlib.Path(os.environ.get("NLSDOF_CLI", ROOT / "target" / "release" / "nlsdof"))
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "-p", "nlsdof-cli"], cwd=ROOT, check=True)
    return str(exe)


@pytest.mark.skipif(not BEAM_24C.exists(), reason="needs ../shared/data beside the repository")
def test_inspect_equals_the_cli_document():
    r = nlsdof.inspect(nlsdof.read_beam_dir(str(BEAM_24C)))
    out = subprocess.run([cli(), "inspect", "--beam-dir", str(BEAM_24C), "--json"],
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    doc = json.loads(out.stdout)
    # the same analysis: every key and number but the timing and the source label
    for k in ("inspect_s", "source"):
        r.pop(k)
        doc.pop(k)
    assert r == doc
    assert r["headline"].startswith("nonlinear: hardening")


def test_inspect_refuses_bad_options_and_data():
    cols = dict(level=["a"] * 5, gamma=[1.0] * 5, f_hz=[10.0, 10.5, 11.0, 11.5, 12.0],
                amplitude=[1e-3] * 5)
    with pytest.raises(ValueError, match="constant"):
        nlsdof.inspect(cols)
    with pytest.raises(ValueError, match="phase"):
        nlsdof.inspect(cols, phase="sometimes")


def test_fit_from_inspect_matches_the_cli():
    """`fit(..., from_inspect=True)` is `fit --from-inspect`: the same fit
    (the CLI's JSON theta and objective, bit for bit) on the demo wing."""
    import tempfile

    import numpy as np

    cli = os.environ.get("NLSDOF_CLI")
    if not cli:
        pytest.skip("NLSDOF_CLI is not set")
    wing = nlsdof.Model.from_toml("examples/har-wing.toml")
    f = np.linspace(5.3, 5.5, 120)
    levels = [0.41, 0.81, 1.23]
    a = np.concatenate([s.amplitude for s in wing.sweep(gamma=levels, f_hz=f)])
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "wing.csv")
        with open(path, "w") as fh:
            fh.write("level,gamma,f_hz,amplitude\n")
            for i, g in enumerate(levels):
                for k in range(len(f)):
                    fh.write(f"L{i},{float(g)!r},{float(f[k])!r},{float(a[i * len(f) + k])!r}\n")
        r = nlsdof.fit(path, from_inspect=True)
        out = subprocess.run([cli, "fit", path, "--from-inspect", "--json"],
                             capture_output=True, text=True, check=True).stdout
    v = json.loads(out)
    assert v["from_inspect"]["start_node"] is not None
    assert r.to_dict()["theta"] == v["theta"]
    assert r.to_dict()["objective"] == v["objective"]
