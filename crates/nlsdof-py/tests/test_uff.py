"""Tests of nlsdof.read_uff / nlsdof.write_uff (Universal File Format
dataset 58/58b).

Oracles: the files written by pyuff 2.5.8 in crates/nlsdof-io/tests/data/uff58
and what pyuff read from them (the JSON sidecars: every header field and
every value, compared bit for bit); round trips (binary 58b bit-exact, ASCII
within the format's digits); and, when pyuff is installed, pyuff reading what
write_uff writes.
"""

import json
import pathlib
import re

import numpy as np
import pytest

import nlsdof

ROOT = pathlib.Path(__file__).resolve().parents[3]
DATA = ROOT / "crates" / "nlsdof-io" / "tests" / "data" / "uff58"
ORACLES = sorted(p for p in DATA.glob("*.uff") if (DATA / (p.name + ".json")).exists())

# pyuff key -> read_uff key (header fields and storage)
SCALARS = {
    "id1": "id1",
    "id2": "id2",
    "id3": "id3",
    "id4": "id4",
    "id5": "id5",
    "func_type": "function_type",
    "func_id": "function_id",
    "ver_num": "version",
    "load_case_id": "load_case",
    "rsp_ent_name": "response_entity",
    "rsp_node": "response_node",
    "rsp_dir": "response_direction",
    "ref_ent_name": "reference_entity",
    "ref_node": "reference_node",
    "ref_dir": "reference_direction",
    "ord_data_type": "ordinate_type",
    "num_pts": "points",
    "abscissa_spacing": "abscissa_spacing",
}
FLOATS = {
    "abscissa_min": "abscissa_min",
    "abscissa_inc": "abscissa_increment",
    "z_axis_value": "z_axis_value",
}
AXES = {
    "abscissa": "abscissa_axis",
    "ordinate": "ordinate_axis",
    "orddenom": "denominator_axis",
    "z_axis": "z_axis",
}
AXIS_FIELDS = {
    "spec_data_type": "specific_data_type",
    "len_unit_exp": "length_exponent",
    "force_unit_exp": "force_exponent",
    "temp_unit_exp": "temperature_exponent",
    "axis_lab": "label",
    "axis_units_lab": "units",
}


def sidecar(path):
    doc = json.loads((DATA / (path.name + ".json")).read_text())
    return [s for s in doc["sets"] if s["type"] == 58]


def same_scalar(want, got, where):
    if isinstance(got, str):
        assert got == str(want).strip(), where
    else:
        assert got == int(want), where


def check_header(want, got, where):
    for k, g in SCALARS.items():
        if k in want:
            same_scalar(want[k], got[g], f"{where}: {k}")
    for k, g in FLOATS.items():
        if k in want:
            assert got[g] == float(want[k]), f"{where}: {k}"
    for prefix, axis in AXES.items():
        for k, g in AXIS_FIELDS.items():
            key = f"{prefix}_{k}"
            if key in want:
                same_scalar(want[key], got[axis][g], f"{where}: {key}")
    assert got["binary"] == bool(int(want["binary"])), where


def test_oracle_files_read_as_pyuff_reads_them():
    assert len(ORACLES) == 19
    functions = 0
    for path in ORACLES:
        sets = sidecar(path)
        got = nlsdof.read_uff(path)
        assert len(got) == len(sets), path.name
        for k, (want, d) in enumerate(zip(sets, got)):
            where = f"{path.name} #{k}"
            assert d["index"] == k
            check_header(want, d, where)
            x = np.array([float(v) for v in want["x"]])
            np.testing.assert_array_equal(d["x"], x, err_msg=where)
            if d["complex"]:
                y = np.array([complex(float(a), float(b)) for a, b in want["data"]])
                assert d["y"].dtype == np.complex128, where
            else:
                y = np.array([float(v) for v in want["data"]])
                assert d["y"].dtype == np.float64, where
            np.testing.assert_array_equal(d["y"], y, err_msg=where)
            functions += 1
    assert functions == 23


def test_selection_and_headers_only():
    path = DATA / "multi.uff"
    full = nlsdof.read_uff(path)
    heads = nlsdof.read_uff(path, headers_only=True)
    assert len(heads) == len(full) == 5
    for h, f in zip(heads, full):
        assert "x" not in h and "y" not in h
        assert h == {k: v for k, v in f.items() if k not in ("x", "y")}
    one = nlsdof.read_uff(path, dataset=2)
    assert [d["index"] for d in one] == [2]
    text = full[3]["id1"]
    chosen = nlsdof.read_uff(path, dataset=text)
    assert [d["id1"] for d in chosen] == [d["id1"] for d in full if text in d["id1"]]
    assert nlsdof.read_uff(path, dataset=99) == []
    with pytest.raises(ValueError, match="give an index"):
        nlsdof.read_uff(path, dataset=1.5)


@pytest.mark.parametrize("path", ORACLES, ids=lambda p: p.name)
def test_round_trip(tmp_path, path):
    got = nlsdof.read_uff(path)
    # binary 58b: bit-exact values, same header
    out = tmp_path / "b.uff"
    nlsdof.write_uff(out, got, binary=True)
    back = nlsdof.read_uff(out)
    assert len(back) == len(got)
    for d, b in zip(got, back):
        assert b["binary"] and b["precision"] == "double"
        for k in list(SCALARS.values())[:15] + list(AXES.values()) + ["z_axis_value"]:
            if k == "z_axis_value":
                # 13-column field: 7 significant digits
                assert b[k] == pytest.approx(d[k], rel=5e-6, abs=0), k
            else:
                assert b[k] == d[k], k
        np.testing.assert_array_equal(b["y"], d["y"])
        if d["abscissa_spacing"] == 0:
            np.testing.assert_array_equal(b["x"], d["x"])
        else:
            np.testing.assert_allclose(b["x"], d["x"], rtol=5e-6)
    # ASCII double: 12 to 14 digits in the data fields, 7 in abscissa fields
    out = tmp_path / "a.uff"
    nlsdof.write_uff(out, got)
    back = nlsdof.read_uff(out)
    for d, b in zip(got, back):
        assert not b["binary"]
        np.testing.assert_allclose(b["y"], d["y"], rtol=5e-13, atol=0)
        np.testing.assert_allclose(b["x"], d["x"], rtol=5e-6, atol=0)
    # writing what was read back gives the same text
    again = tmp_path / "a2.uff"
    nlsdof.write_uff(again, back)
    assert again.read_text() == out.read_text()


def test_write_new_datasets(tmp_path):
    t = np.arange(100) / 1024.0
    accel = np.round(np.sin(2 * np.pi * 5 * t), 9)
    f = np.array([1.0, 2.5, 4.0, 8.0])
    h = np.array([1 + 2j, -0.5j, 3.25, -1e-3 + 4e-3j])
    sets = [
        {
            "id1": "base acceleration",
            "function_type": 1,
            "abscissa_min": 0.0,
            "abscissa_increment": 1 / 1024,
            "abscissa_axis": {"specific_data_type": 17, "label": "Time", "units": "s"},
            "ordinate_axis": {"specific_data_type": 12, "length_exponent": 1, "units": "m/s^2"},
            "y": accel,
        },
        {
            "id1": "receptance",
            "function_type": 4,
            "response_node": 2,
            "response_direction": 3,
            "x": f,
            "y": h,
        },
    ]
    out = tmp_path / "new.uff"
    nlsdof.write_uff(out, sets)
    a, b = nlsdof.read_uff(out)
    assert (a["function_type"], a["id1"], a["abscissa_spacing"]) == (1, "base acceleration", 1)
    assert a["ordinate_axis"] == {
        "specific_data_type": 12,
        "length_exponent": 1,
        "force_exponent": 0,
        "temperature_exponent": 0,
        "label": "NONE",
        "units": "m/s^2",
    }
    np.testing.assert_array_equal(a["y"], accel)  # 9 decimals: exact in E20.12
    assert a["abscissa_increment"] == 1 / 1024  # 9.765625e-4: 7 digits, exact
    assert (b["response_node"], b["response_direction"], b["id2"]) == (2, 3, "NONE")
    np.testing.assert_array_equal(b["x"], f)
    np.testing.assert_array_equal(b["y"], h)
    # a single dict is one dataset
    nlsdof.write_uff(out, sets[1])
    assert len(nlsdof.read_uff(out)) == 1


def test_bad_input_is_a_value_error(tmp_path):
    out = tmp_path / "bad.uff"
    good = {"x": [1.0, 2.0], "y": [1.0, 2.0]}
    cases = [
        ({"x": [1.0, 2.0]}, "no 'y'"),
        ({**good, "colour": "red"}, "unknown key 'colour'"),
        ({**good, "x": [1.0]}, "x has 1 values but y has 2"),
        ({**good, "function_type": "frf"}, "function_type = 'frf' is not an int"),
        ({**good, "response_direction": 7}, "response direction"),
        ({**good, "id1": "x" * 81}, "ID line 1"),
        ({**good, "ordinate_axis": {"unit": "m"}}, "unknown key 'unit'"),
        ({"y": [1.0, 2.0]}, "needs abscissa_min and abscissa_increment"),
        ({**good, "y": [1.0, float("nan")]}, "not finite"),
        ({**good, "abscissa_spacing": 2}, "abscissa_spacing 2"),
    ]
    for d, want in cases:
        with pytest.raises(ValueError, match=re.escape(want)):
            nlsdof.write_uff(out, [d])
        assert not out.exists(), want
    with pytest.raises(ValueError, match="must be a dict"):
        nlsdof.write_uff(out, [1])
    with pytest.raises(ValueError, match="cannot read"):
        nlsdof.read_uff(tmp_path / "missing.uff")
    (tmp_path / "junk.uff").write_text("hello\n")
    with pytest.raises(ValueError):
        nlsdof.read_uff(tmp_path / "junk.uff")


def test_pyuff_reads_what_write_uff_writes(tmp_path):
    pyuff = pytest.importorskip("pyuff")
    f = np.linspace(2.0, 20.0, 37)
    h = 1.0 / (100.0 - (2 * np.pi * f / 6.0) ** 2 + 1j * 0.3 * f)
    sets = [
        {
            "id1": "time",
            "function_type": 1,
            "abscissa_min": 0.5,
            "abscissa_increment": 0.01,
            "abscissa_axis": {"specific_data_type": 17, "label": "Time", "units": "s"},
            "y": np.cos(np.arange(50) * 0.1),
        },
        {
            "id1": "FRF uneven",
            "function_type": 4,
            "response_node": 3,
            "reference_node": 1,
            "x": np.round(f, 5),
            "y": h,
        },
    ]
    for binary in (False, True):
        out = tmp_path / f"w{int(binary)}.uff"
        nlsdof.write_uff(out, sets, binary=binary)
        read = pyuff.UFF(str(out)).read_sets()
        if isinstance(read, dict):
            read = [read]
        assert [s["type"] for s in read] == [58, 58]
        rtol = 0 if binary else 5e-13
        for want, got in zip(sets, read):
            assert got["id1"].strip() == want["id1"]
            assert int(got["func_type"]) == want["function_type"]
            np.testing.assert_allclose(got["data"], want["y"], rtol=rtol, atol=0)
        np.testing.assert_allclose(read[0]["x"], 0.5 + 0.01 * np.arange(50), rtol=1e-12)
        np.testing.assert_array_equal(read[1]["x"], np.round(f, 5))
        assert int(read[1]["rsp_node"]) == 3 and int(read[1]["ref_node"]) == 1
