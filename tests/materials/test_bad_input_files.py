"""Issue 21: malformed optical-constant files and CLI arguments are one-line errors (exit 2),
never a traceback, never a silently wrong material; messages never echo file contents."""

import numpy as np
import pytest

from nmmm.cli import main
from nmmm.errors import DataFileError, InvalidInputError
from nmmm.materials import Constant
from nmmm.materials.files import read_csv, read_yaml, write_csv
from nmmm.spectra import wavelength_grid


def _csv(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("rows, match", [
    ("0,1.5,0\n500,1.5,0\n", "wavelength 0 nm at line 2 is not > 0"),
    ("400,1e308,0\n500,1.5,0\n", "n = 1e\\+308 at line 2 is above 1000"),
    ("400,-1.5,0\n500,1.5,0\n", "n = -1.5 at line 2; nmmm needs n > 0"),
    ("400,0,0\n500,1.5,0\n", "n = 0 at line 2"),
    ("400,1.5,1e5\n500,1.5,0\n", "k = 100000 at line 2"),
    ("0.3,1.5,0\n0.9,1.5,0\n", "look like µm under an nm header"),
])
def test_csv_values_no_material_has_are_refused(tmp_path, rows, match):
    p = _csv(tmp_path, "m.csv", "wavelength_nm,n,k\n" + rows)
    with pytest.raises(DataFileError, match=match):
        read_csv(p)


def test_nm_values_under_a_um_header_are_refused(tmp_path):
    p = _csv(tmp_path, "m.csv", "wavelength_um,n,k\n1500,1.5,0\n2500,1.5,0\n")
    with pytest.raises(DataFileError, match="look like nm under a µm header"):
        read_csv(p)


def test_binary_and_utf16_files_are_data_file_errors(tmp_path):
    u = tmp_path / "u.csv"
    u.write_text("wavelength_nm,n,k\n400,1.5,0\n500,1.5,0\n", encoding="utf-16")
    b = tmp_path / "b.csv"
    b.write_bytes(bytes(range(256)) * 4)
    latin = tmp_path / "l.csv"
    latin.write_bytes("# name: verre trempé\nwavelength_nm,n,k\n400,1.5,0\n500,1.5,0\n".encode("latin-1"))
    for p in (u, b):
        with pytest.raises(DataFileError, match="binary or UTF-16"):
            read_csv(p)
    with pytest.raises(DataFileError, match="not UTF-8"):
        read_csv(latin)
    y = tmp_path / "u.yml"
    y.write_text("DATA: []\n", encoding="utf-16")
    with pytest.raises(DataFileError, match="binary or UTF-16"):
        read_yaml(y)


@pytest.mark.parametrize("text, match", [
    ("- a\n- b\n", "got a list"),
    ("DATA: [1, 2]\n", "DATA must be a list of mappings"),
    ("DATA: 3\n", "DATA must be a list of mappings"),
    ("DATA:\n  - type: tabulated\n    data: 1 2\n", "must be 'tabulated nk'"),
    ("DATA:\n  - type: tabulated nk\n    data: |\n      0.4 -1.5 0\n      0.5 1.5 0\n", "n = -1.5"),
    ("a: [" * 3000 + "]" * 3000 + "\n", "YAML"),
])
def test_malformed_yaml_files_are_data_file_errors(tmp_path, text, match):
    p = tmp_path / "m.yml"
    p.write_text(text)
    with pytest.raises(DataFileError, match=match):
        read_yaml(p)


def test_messages_never_echo_a_secret_line(tmp_path):
    secret = "root:x:0:0:root:/root:/bin/bash"
    for text in (f"{secret}\n1,2,3\n", f"wavelength_nm,n,k\n{secret},1,2\n400,1,0\n",
                 f"SECRET_TOKEN=abc/def,n,k\n400,1.5,0\n500,1.5,0\n"):
        p = _csv(tmp_path, "s.csv", text)
        with pytest.raises(DataFileError) as e:
            read_csv(p)
        assert "root:" not in str(e.value) and "SECRET" not in str(e.value) and "abc/def" not in str(e.value)
    y = tmp_path / "s.yml"
    y.write_text(f"DATA:\n  - type: tabulated nk\n    data: |\n      {secret}\n")
    with pytest.raises(DataFileError) as e:
        read_yaml(y)
    assert "root:" not in str(e.value)
    y.write_text(f"DATA: [{secret}\n")  # invalid YAML: only the line and column are told
    with pytest.raises(DataFileError) as e:
        read_yaml(y)
    assert "root:" not in str(e.value) and "line" in str(e.value)


def test_write_csv_is_atomic_and_round_trips(tmp_path, monkeypatch):
    w = wavelength_grid(400, 700, 50)
    p = write_csv(Constant(nk=1.5 + 0.01j, name="glass"), tmp_path / "g.csv", w)
    np.testing.assert_allclose(read_csv(p).nk(w), 1.5 + 0.01j)
    before = p.read_bytes()
    import nmmm.atomic_io as aio

    def full(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(aio.os, "fsync", full)
    with pytest.raises(DataFileError, match="No space left"):
        write_csv(Constant(nk=2.0, name="other"), p, w)
    assert p.read_bytes() == before and sorted(x.name for x in tmp_path.iterdir()) == ["g.csv"]


def test_wavelength_grid_refuses_what_would_exhaust_memory():
    with pytest.raises(InvalidInputError, match="more than 1,000,000"):
        wavelength_grid(380, 780, 1e-9)
    with pytest.raises(InvalidInputError, match="> 0 nm"):
        wavelength_grid(0, 780, 5)
    with pytest.raises(InvalidInputError, match="finite"):
        wavelength_grid(380, float("inf"), 5)


@pytest.mark.parametrize("args, needle", [
    (["materials", "show", "main/Au/Johnson", "--points", "-5"], "--points"),
    (["materials", "show", "main/Au/Johnson", "--points", "1000000000"], "--points"),
    (["ema", "mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson:abc"], "FRACTION must be a number"),
    (["ema", "mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson:0.1:spheroid=x"], "ASPECT_RATIO"),
    (["ema", "mix", "--host", "main/SiO2/Malitson", "--inclusion", "main/Au/Johnson:0.1", "--step-nm", "1e-9"],
     "more than 1,000,000"),
])
def test_cli_arguments_are_one_line_errors_with_exit_2(args, needle, capsys):
    rc = main(args)
    cap = capsys.readouterr()
    assert rc == 2, cap.err
    assert cap.err.startswith("error: ") and needle in cap.err and len(cap.err.strip().splitlines()) == 1, cap.err
    assert "Traceback" not in cap.err + cap.out


def test_materials_show_of_bad_files_exits_2(tmp_path, capsys):
    for name, text in [("z.csv", "wavelength_nm,n,k\n0,1.5,0\n500,1.5,0\n"), ("l.yml", "- a\n- b\n"),
                       ("d.yml", "DATA: [1, 2]\n")]:
        p = _csv(tmp_path, name, text)
        rc = main(["materials", "show", str(p)])
        err = capsys.readouterr().err
        assert rc == 2 and err.startswith("error: ") and "Traceback" not in err, err


@pytest.mark.parametrize("text, match", [
    # extra columns are refused, never dropped silently
    ("wavelength_nm,n,k,T\n400,1.5,0.01,99\n500,1.6,0.02,98\n", r"column 4 \('T'\) is not one nmmm reads"),
    ("wavelength_nm,n,k\n400,1.5,0.01,99\n500,1.6,0.02,98\n", r"line 2 \('400,1.5,0.01,99'\) has 4 values.*header names 3"),
    ("wavelength_nm,n,k\n400,1.5,0.01\n500,1.6,0.02\n600,1.7,0.03,5\n", r"line 4 .* has 4 values"),
    # a row is named by its line in the file, comment and blank lines counted
    ("# name: x\n# reference: y\nwavelength_nm,n,k\n\n400,1.5,0\n# note\n500,-1.5,0\n", r"n = -1.5 at line 7"),
    ("# a comment\nwavelength_nm,n,k\n400,1.5,0\n500,x,0\n", r"line 4 \('500,x,0'\) is not numeric"),
    ("# a comment\nwavelength_nm,n,k\n400,1.5,0\n\n500,1.5,-0.1\n", r"k < 0 at line 5"),
    # % and tab are shown as written; semicolon / tab files are told to use commas
    ("wavelength_nm,n,k %\n400,1.5,1\n500,1.6,2\n", r"got 'n,k %'"),
    ("wavelength_nm;n;k\n400;1,5;0,01\n500;1,6;0,02\n", r"'wavelength_nm;n;k'.*semicolons: use commas"),
    ("wavelength_nm\tn\tk\n400\t1.5\t0\n500\t1.6\t0\n", r"'wavelength_nm\\tn\\tk'.*tabs: use commas"),
    ("wavelength_nm,n,k\n400,1,5,0,01\n500,1,6,0,02\n", r"line 2 .* has 5 values.*decimal commas"),
])
def test_csv_extra_columns_line_numbers_and_separator_hints(tmp_path, text, match):
    with pytest.raises(DataFileError, match=match):
        read_csv(_csv(tmp_path, "m.csv", text))
