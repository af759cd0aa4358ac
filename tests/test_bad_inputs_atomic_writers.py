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
