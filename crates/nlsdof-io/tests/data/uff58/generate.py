# Regenerate: python3 -m venv /tmp/uffv && /tmp/uffv/bin/pip install pyuff==2.5.8 numpy
#             && /tmp/uffv/bin/python crates/nlsdof-io/tests/data/uff58/generate.py
"""Oracle test files of universal file dataset 58 / 58b for crates/nlsdof-io/tests/uff58.rs.

Writes small files (tens of points) covering ASCII and binary, single and
double precision, real and complex, even and uneven abscissa, the function
types a lab writes, and a file of several datasets with datasets 151 and
164 interleaved. Then reads every file back with pyuff and writes, next to
it, FILE.json: every dataset as pyuff reads it, every header field and every
value. Floats are stored as Python repr() strings (shortest round-trip
decimal), so the Rust test compares them bit for bit without depending on a
JSON float parser.

Where pyuff 2.5.8 cannot write a variant (binary single precision, binary big
endian, transmissibility), the file is written here with the fixed-width
records of the format and the numpy byte layout, and pyuff still is the
oracle: the JSON is what pyuff reads from it.

Run from anywhere; the files are written next to this script. The output is
deterministic (fixed seeds, fixed dates).
"""

import json
import os
import struct
import sys

import numpy as np
import pyuff

assert pyuff.__version__ == "2.5.8", f"pinned pyuff 2.5.8, found {pyuff.__version__}"

HERE = os.path.dirname(os.path.abspath(__file__))


def path(name):
    return os.path.join(HERE, name)


def fresh(name):
    p = path(name)
    if os.path.exists(p):
        os.remove(p)
    return p


def base58(func_type, x, data, spacing, **kw):
    d = dict(
        type=58,
        binary=0,
        id1="NONE",
        id2="NONE",
        id3="NONE",
        id4="NONE",
        id5="NONE",
        func_type=func_type,
        func_id=0,
        ver_num=0,
        load_case_id=0,
        rsp_ent_name="NONE",
        rsp_node=1,
        rsp_dir=3,
        ref_ent_name="NONE",
        ref_node=1,
        ref_dir=3,
        abscissa_spacing=spacing,
        z_axis_value=0.0,
        abscissa_spec_data_type=18,
        abscissa_len_unit_exp=0,
        abscissa_force_unit_exp=0,
        abscissa_temp_unit_exp=0,
        abscissa_axis_lab="Frequency",
        abscissa_axis_units_lab="Hz",
        ordinate_spec_data_type=12,
        ordinate_len_unit_exp=1,
        ordinate_force_unit_exp=0,
        ordinate_temp_unit_exp=0,
        ordinate_axis_lab="Acceleration",
        ordinate_axis_units_lab="m/s^2",
        orddenom_spec_data_type=13,
        orddenom_len_unit_exp=0,
        orddenom_force_unit_exp=1,
        orddenom_temp_unit_exp=0,
        orddenom_axis_lab="Force",
        orddenom_axis_units_lab="N",
        z_axis_spec_data_type=0,
        z_axis_len_unit_exp=0,
        z_axis_force_unit_exp=0,
        z_axis_temp_unit_exp=0,
        z_axis_axis_lab="NONE",
        z_axis_axis_units_lab="NONE",
        x=np.asarray(x, dtype=float),
        data=data,
    )
    d.update(kw)
    return d


def write_pyuff(name, dsets, force_double=True):
    p = fresh(name)
    pyuff.UFF(p).write_sets(dsets, mode="add", force_double=force_double)


def rng(seed):
    return np.random.default_rng(seed)


def complex_values(seed, n):
    r = rng(seed)
    return r.normal(size=n) * 10.0 ** r.uniform(-4, 2, n) + 1j * r.normal(size=n) * 10.0 ** r.uniform(-4, 2, n)


def real_values(seed, n):
    r = rng(seed)
    return r.normal(size=n) * 10.0 ** r.uniform(-6, 3, n)


def patch_func_type(name, old, new):
    """pyuff 2.5.8 refuses to write some function types (5, ...): write
    another type and change record 6 field 1 (columns 1-5)."""
    p = path(name)
    lines = open(p, "rb").read().split(b"\n")
    assert int(lines[7][:5]) == old
    lines[7] = b"%5d" % new + lines[7][5:]
    open(p, "wb").write(b"\n".join(lines))


# ------------------------------------------------------ hand-written 58b


def header_lines(d, ord_type, n, spacing, xmin, dx):
    """Records 1-11 with the widths of the format."""
    out = []
    for k in range(1, 6):
        out.append("%-80s" % d["id%d" % k])
    out.append(
        "%5i%10i%5i%10i %10s%10i%4i %10s%10i%4i"
        % (
            d["func_type"], d["func_id"], d["ver_num"], d["load_case_id"],
            d["rsp_ent_name"], d["rsp_node"], d["rsp_dir"],
            d["ref_ent_name"], d["ref_node"], d["ref_dir"],
        )
    )
    out.append("%10i%10i%10i%13.5e%13.5e%13.5e" % (ord_type, n, spacing, xmin, dx, d["z_axis_value"]))
    for a in ["abscissa", "ordinate", "orddenom", "z_axis"]:
        lab = "z_axis_axis_lab" if a == "z_axis" else a + "_axis_lab"
        units = "z_axis_axis_units_lab" if a == "z_axis" else a + "_axis_units_lab"
        out.append(
            "%10i%5i%5i%5i %-20s %-20s"
            % (
                d[a + "_spec_data_type"], d[a + "_len_unit_exp"], d[a + "_force_unit_exp"],
                d[a + "_temp_unit_exp"], d[lab], d[units],
            )
        )
    return "".join(line + "\n" for line in out).encode()


def binary_block(d, single, big, newline_before_end=False, declared_bytes=None):
    x = np.asarray(d["x"], dtype=float)
    data = np.asarray(d["data"])
    n = len(data)
    even = d["abscissa_spacing"] == 1
    cplx = np.iscomplexobj(data)
    ord_type = {(False, True): 2, (False, False): 4, (True, True): 5, (True, False): 6}[(cplx, single)]
    cols = [] if even else [x]
    cols += [data.real, data.imag] if cplx else [data]
    values = np.column_stack(cols).ravel()
    dt = (">" if big else "<") + ("f4" if single else "f8")
    raw = values.astype(dt).tobytes()
    nb = len(raw) if declared_bytes is None else declared_bytes
    head = "%6i\n%6ib%6i%6i%12i%12i%6i%6i%12i%12i\n" % (-1, 58, 2 if big else 1, 2, 11, nb, 0, 0, 0, 0)
    xmin = x[0] if even else 0.0
    dx = (x[1] - x[0]) if even else 0.0
    out = head.encode() + header_lines(d, ord_type, n, 1 if even else 0, xmin, dx) + raw
    if newline_before_end:
        out += b"\n"
    return out + b"%6i\n" % -1


def write_raw(name, blocks):
    open(fresh(name), "wb").write(b"".join(blocks))


# ------------------------------------------------------------- JSON


def f(v):
    return repr(float(v))


def jsonable(d):
    out = {}
    for k, v in d.items():
        if isinstance(v, np.ndarray):
            if np.iscomplexobj(v):
                out[k] = [[f(c.real), f(c.imag)] for c in v]
            else:
                out[k] = [f(c) for c in v]
        elif isinstance(v, (float, np.floating)):
            out[k] = f(v)
        elif isinstance(v, (bool, np.bool_)):
            out[k] = int(v)
        elif isinstance(v, (int, np.integer)):
            out[k] = int(v)
        elif v is None or isinstance(v, str):
            out[k] = v
        else:
            raise TypeError(f"{k}: {type(v)}")
    return out


def oracle(name):
    u = pyuff.UFF(path(name))
    n = u.get_n_sets()
    sets = [u.read_sets(k) for k in range(n)]
    heads = [u.read_sets(k, header_only=True) for k in range(n)]
    for s, h in zip(sets, heads):
        if s["type"] == 58:
            for k in h:
                if k not in ("x", "data"):
                    assert h[k] == s[k], (name, k)
    doc = {
        "pyuff": pyuff.__version__,
        "file": name,
        "set_types": [int(t) for t in u.get_set_types()],
        "sets": [jsonable(s) for s in sets],
    }
    with open(path(name + ".json"), "w") as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")


# ------------------------------------------------------------- files

FILES = []


def made(name):
    FILES.append(name)


def main():
    fs = 1024.0
    t = np.arange(40) / fs
    f_even = 2.5 + 0.5 * np.arange(30)
    f_uneven = np.round(np.geomspace(1.0, 900.0, 24), 3)

    # ASCII, double precision (pyuff's default), the four data cases
    write_pyuff(
        "ascii_double_real_even_time.uff",
        [base58(1, t, real_values(1, 40), 1,
                id1="Simulated response x(t)", id2="Run 7", id3="11-Mar-24 10:11:12",
                id4="Load case 1", id5="nlsdof generate.py",
                func_id=12, ver_num=3, load_case_id=0, rsp_ent_name="BEAM", rsp_node=101,
                rsp_dir=-3, ref_ent_name="SHAKER", ref_node=1, ref_dir=3,
                abscissa_spec_data_type=17, abscissa_axis_lab="Time", abscissa_axis_units_lab="s",
                ordinate_spec_data_type=8, ordinate_axis_lab="Displacement", ordinate_axis_units_lab="m",
                orddenom_spec_data_type=0, orddenom_len_unit_exp=0, orddenom_force_unit_exp=0,
                orddenom_axis_lab="NONE", orddenom_axis_units_lab="NONE")],
    )
    made("ascii_double_real_even_time.uff")

    write_pyuff(
        "ascii_double_real_uneven_autospectrum.uff",
        [base58(2, f_uneven, np.abs(real_values(2, 24)), 0, id1="Auto spectrum 5+Y",
                rsp_node=5, rsp_dir=2, ref_node=5, ref_dir=2, ordinate_axis_units_lab="(m/s^2)^2",
                ordinate_len_unit_exp=2, orddenom_spec_data_type=0, orddenom_force_unit_exp=0)],
    )
    made("ascii_double_real_uneven_autospectrum.uff")

    write_pyuff(
        "ascii_double_complex_even_frf.uff",
        [base58(4, f_even, complex_values(3, 30), 1, id1="FRF 2+Z/1+Z", rsp_node=2,
                z_axis_value=0.25, z_axis_spec_data_type=1, z_axis_len_unit_exp=-1,
                z_axis_axis_lab="Level", z_axis_axis_units_lab="g")],
    )
    made("ascii_double_complex_even_frf.uff")

    write_pyuff(
        "ascii_double_complex_uneven_frf.uff",
        [base58(4, f_uneven, complex_values(4, 24), 0, id1="FRF uneven", rsp_node=3, rsp_dir=1,
                ref_node=9, ref_dir=-2, func_id=4, ver_num=1)],
    )
    made("ascii_double_complex_uneven_frf.uff")

    # ASCII, single precision (force_double=False, ord_data_type 2 / 5)
    write_pyuff(
        "ascii_single_real_even_coherence.uff",
        [base58(6, f_even, np.clip(np.abs(real_values(5, 30)), 0, 1), 1, ord_data_type=2,
                id1="Coherence", ordinate_spec_data_type=0, ordinate_len_unit_exp=0,
                ordinate_axis_lab="Coherence", ordinate_axis_units_lab="NONE")],
        force_double=False,
    )
    made("ascii_single_real_even_coherence.uff")

    write_pyuff(
        "ascii_single_real_uneven_psd.uff",
        [base58(9, f_uneven, np.abs(real_values(6, 24)), 0, ord_data_type=2, id1="PSD",
                ordinate_axis_units_lab="(m/s^2)^2/Hz")],
        force_double=False,
    )
    made("ascii_single_real_uneven_psd.uff")

    write_pyuff(
        "ascii_single_complex_even_crossspectrum.uff",
        [base58(3, f_even, complex_values(7, 30), 1, ord_data_type=5, id1="Cross spectrum",
                rsp_node=4, ref_node=1)],
        force_double=False,
    )
    made("ascii_single_complex_even_crossspectrum.uff")

    # transmissibility (5): pyuff refuses to write it; written as FRF, then
    # record 6 field 1 changed
    write_pyuff(
        "ascii_single_complex_uneven_transmissibility.uff",
        [base58(4, f_uneven, complex_values(8, 24), 0, ord_data_type=5, id1="Transmissibility",
                orddenom_spec_data_type=12, orddenom_len_unit_exp=1, orddenom_force_unit_exp=0,
                orddenom_axis_lab="Acceleration", orddenom_axis_units_lab="m/s^2")],
        force_double=False,
    )
    patch_func_type("ascii_single_complex_uneven_transmissibility.uff", 4, 5)
    made("ascii_single_complex_uneven_transmissibility.uff")

    # Binary 58b written by pyuff (little endian, double). pyuff 2.5.8
    # declares num_pts*8 bytes even for complex or uneven data (16 or 24
    # bytes a point): the reader must not trust that count.
    write_pyuff("binary_double_complex_even_frf.uff",
                [base58(4, f_even, complex_values(9, 30), 1, binary=1, id1="FRF 58b")])
    made("binary_double_complex_even_frf.uff")
    write_pyuff("binary_double_real_even_time.uff",
                [base58(1, t, real_values(10, 40), 1, binary=1, id1="Time 58b",
                        abscissa_spec_data_type=17, abscissa_axis_lab="Time", abscissa_axis_units_lab="s")])
    made("binary_double_real_even_time.uff")
    write_pyuff("binary_double_real_uneven_autospectrum.uff",
                [base58(2, f_uneven, np.abs(real_values(11, 24)), 0, binary=1, id1="Auto 58b")])
    made("binary_double_real_uneven_autospectrum.uff")
    write_pyuff("binary_double_complex_uneven_crossspectrum.uff",
                [base58(3, f_uneven, complex_values(12, 24), 0, binary=1, id1="Cross 58b")])
    made("binary_double_complex_uneven_crossspectrum.uff")

    # Binary 58b pyuff cannot write: single precision, big endian, exact
    # byte counts, a line feed before the closing -1 (as some commercial
    # programs write it)
    write_raw("binary_single_real_even_time_le.uff",
              [binary_block(base58(1, t, real_values(13, 40), 1, id1="Time single LE",
                                   abscissa_spec_data_type=17, abscissa_axis_lab="Time",
                                   abscissa_axis_units_lab="s"), single=True, big=False)])
    made("binary_single_real_even_time_le.uff")
    write_raw("binary_single_complex_even_frf_be.uff",
              [binary_block(base58(4, f_even, complex_values(14, 30), 1, id1="FRF single BE"),
                            single=True, big=True)])
    made("binary_single_complex_even_frf_be.uff")
    write_raw("binary_single_complex_uneven_crossspectrum_le.uff",
              [binary_block(base58(3, f_uneven, complex_values(15, 24), 0, id1="Cross single LE"),
                            single=True, big=False)])
    made("binary_single_complex_uneven_crossspectrum_le.uff")
    write_raw("binary_double_complex_uneven_frf_be.uff",
              [binary_block(base58(4, f_uneven, complex_values(16, 24), 0, id1="FRF double BE"),
                            single=False, big=True)])
    made("binary_double_complex_uneven_frf_be.uff")
    write_raw("binary_double_real_uneven_coherence_be_lf.uff",
              [binary_block(base58(6, f_uneven, np.clip(np.abs(real_values(17, 24)), 0, 1), 0,
                                   id1="Coherence BE, LF before -1"),
                            single=False, big=True, newline_before_end=True)])
    made("binary_double_real_uneven_coherence_be_lf.uff")

    # Several datasets, other types interleaved (151 header, 164 units)
    p = fresh("multi.uff")
    u = pyuff.UFF(p)
    u.write_sets(
        [
            dict(type=151, model_name="nlsdof oracle", description="several functions",
                 db_app="generate.py", date_db_created="11-Mar-24", time_db_created="10:11:12",
                 date_db_saved="11-Mar-24", time_db_saved="10:11:12", program="pyuff 2.5.8",
                 date_file_written="11-Mar-24", time_file_written="10:11:12"),
            dict(type=164, units_code=1, units_description="SI", temp_mode=2,
                 length=1.0, force=1.0, temp=1.0, temp_offset=273.15),
            base58(1, t, real_values(20, 40), 1, id1="Channel 1 time", rsp_node=1, rsp_dir=3,
                   abscissa_spec_data_type=17, abscissa_axis_lab="Time", abscissa_axis_units_lab="s"),
            base58(4, f_even, complex_values(21, 30), 1, id1="FRF 2+Z/1+Z", rsp_node=2, rsp_dir=3),
            base58(4, f_even, complex_values(22, 30), 1, binary=1, id1="FRF 3+Y/1+Z", rsp_node=3,
                   rsp_dir=2),
            dict(type=164, units_code=2, units_description="mm N", temp_mode=2,
                 length=1000.0, force=1.0, temp=1.0, temp_offset=273.15),
            base58(6, f_even, np.clip(np.abs(real_values(23, 30)), 0, 1), 1, id1="Coherence 2+Z/1+Z",
                   rsp_node=2, rsp_dir=3),
            base58(2, f_uneven, np.abs(real_values(24, 24)), 0, id1="Auto 1+Z", rsp_node=1, rsp_dir=3),
        ],
        mode="add",
    )
    made("multi.uff")

    # CRLF line ends (Windows programs)
    raw = open(path("ascii_double_complex_even_frf.uff"), "rb").read()
    open(fresh("crlf_ascii_double_complex_even_frf.uff"), "wb").write(raw.replace(b"\n", b"\r\n"))
    made("crlf_ascii_double_complex_even_frf.uff")

    for name in FILES:
        oracle(name)
    with open(path("files.txt"), "w") as fh:
        fh.write("".join(n + "\n" for n in FILES))
    print(f"{len(FILES)} files and their JSON written to {HERE}", file=sys.stderr)


if __name__ == "__main__":
    main()
