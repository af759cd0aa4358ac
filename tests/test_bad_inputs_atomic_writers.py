"""Issue 21, integrity: the microstructure, render and ellipsometry writers are atomic — a failure
while writing (a full disk, a crash) leaves the previous file untouched and no partial file under
the name, and no temporary file behind."""

import numpy as np
import pytest

from nmmm.errors import DataFileError


def _fail_replace(monkeypatch):
    import os

    def boom(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", boom)


@pytest.mark.parametrize("suffix", [".npz", ".tif"])
def test_save_microstructure_is_atomic(tmp_path, monkeypatch, suffix):
    from nmmm.microstructure import Microstructure, load_microstructure, save_microstructure

    m = Microstructure(np.arange(24).reshape(4, 6) % 2, voxel_nm=5.0)
    path = tmp_path / f"cell{suffix}"
    save_microstructure(m, path)
    before = path.read_bytes()
    assert np.array_equal(load_microstructure(path).labels, m.labels)
    m2 = Microstructure(np.ones((4, 6), dtype=int), voxel_nm=5.0)
    with monkeypatch.context() as mp:
        _fail_replace(mp)
        with pytest.raises(DataFileError, match="No space left"):
            save_microstructure(m2, path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]


def test_spectral_exr_is_atomic(tmp_path, monkeypatch):
    pytest.importorskip("OpenEXR")
    from nmmm.appearance.render.exr import write_spectral_exr

    w = np.array([450.0, 550.0, 650.0])
    v = np.full((4, 5, 3), 0.5)
    path = write_spectral_exr(tmp_path / "img.exr", w, v)
    before = path.read_bytes()
    with monkeypatch.context() as mp:
        _fail_replace(mp)
        with pytest.raises(DataFileError):
            write_spectral_exr(path, w, v * 2)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["img.exr"]


def test_ellipsometry_csv_writers_are_atomic(tmp_path, monkeypatch):
    from nmmm.ellipsometry.data import EllipsometryData, read_csv, write_csv

    d = EllipsometryData([400.0, 500.0], 70.0, [20.0, 21.0], [100.0, 110.0])
    path = write_csv(d, tmp_path / "d.csv")
    before = path.read_bytes()
    with monkeypatch.context() as mp:
        _fail_replace(mp)
        with pytest.raises(DataFileError):
            write_csv(d, path)
    assert path.read_bytes() == before and len(read_csv(path)) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.csv"]


def test_atomic_outputs_get_the_usual_file_modes(tmp_path):
    """mkstemp / mkdtemp make 0600 / 0700; an output file gets 0666 & ~umask (or the mode of the file
    it replaces) and a new output folder 0777 & ~umask, as plain open / mkdir would give."""
    import os
    import stat

    from nmmm.atomic_io import atomic_output_dir, atomic_write_text

    old = os.umask(0o022)
    try:
        p = atomic_write_text(tmp_path / "report.html", "<html></html>")
        assert stat.S_IMODE(p.stat().st_mode) == 0o644
        os.chmod(p, 0o640)
        atomic_write_text(p, "again")
        assert stat.S_IMODE(p.stat().st_mode) == 0o640
        os.umask(0o002)
        q = atomic_write_text(tmp_path / "table.csv", "a,b\n")
        assert stat.S_IMODE(q.stat().st_mode) == 0o664
        with atomic_output_dir(tmp_path / "run") as d:
            (d / "x.csv").write_text("1\n")
        assert stat.S_IMODE((tmp_path / "run").stat().st_mode) == 0o775
    finally:
        os.umask(old)
