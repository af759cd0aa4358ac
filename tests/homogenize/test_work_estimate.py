"""Issue 21, unbounded work: an FFT homogenization is estimated (memory, time) before it starts and
refused beyond the limits with the estimate and the option that raises them, instead of running for
tens of minutes (a 4096² three-phase metal cell) or exhausting memory (4096³)."""

import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.homogenize.fft import fft_permittivity
from nmmm.homogenize.work_estimate import FFT_MAX_MEMORY_GB, check_fft_work, estimate_fft_work


def test_estimate_scales_with_the_cell():
    a = estimate_fft_work((64, 64, 64))
    b = estimate_fft_work((128, 128, 128))
    assert b["voxels"] == 8 * a["voxels"]
    assert b["memory_gb"] == pytest.approx(8 * a["memory_gb"])
    assert estimate_fft_work((64, 64, 64), dtype="complex64")["memory_gb"] == pytest.approx(a["memory_gb"] / 2)
    assert estimate_fft_work((64, 64), metal=True)["seconds"] > estimate_fft_work((64, 64))["seconds"]


def test_4096_cubed_is_refused_with_memory_and_time():
    with pytest.raises(InvalidInputError, match=r"4096 x 4096 x 4096 cell .*memory 2\.64e\+04 GB > .*max_memory_gb"
                                                r".*days > 30 min \(max_minutes="):
        check_fft_work((4096, 4096, 4096))
    # raising both limits lets the estimate through (the caller's decision)
    e = check_fft_work((4096, 4096, 4096), max_memory_gb=float("inf"), max_minutes=float("inf"))
    assert e["memory_gb"] > FFT_MAX_MEMORY_GB


def test_4096_squared_metal_cell_is_refused_at_once_and_runs_when_allowed_small():
    lab = np.random.default_rng(0).integers(0, 3, (4096, 4096)).astype(np.uint8)
    with pytest.raises(InvalidInputError, match=r"4096 x 4096 cell .*metal contrast.*min > 30 min.*--max-minutes"):
        fft_permittivity(lab, {0: 2.25, 1: -50 + 2j, 2: 3.0}, check_periodic=False)
    with pytest.raises(InvalidInputError, match="memory .* > 0.001 GB"):
        fft_permittivity(lab[:64, :64], {0: 2.25, 1: 4.0, 2: 3.0}, check_periodic=False, max_memory_gb=0.001)
    r = fft_permittivity(lab[:32, :32], {0: 2.25, 1: 4.0, 2: 3.0}, check_periodic=False, max_minutes=1)
    assert np.isfinite(r.tensor).all()


def test_cli_limits(tmp_path, capsys):
    from nmmm.cli import main
    from nmmm.microstructure import Microstructure, save_microstructure

    lab = np.zeros((64, 64), dtype=np.uint8)
    lab[:32] = 1
    cell = save_microstructure(Microstructure(lab, voxel_nm=10.0), tmp_path / "cell.npz")
    args = ["homogenize", "run", str(cell), "--eps", "0=2.25", "--eps", "1=4"]
    assert main(args + ["--max-memory-gb", "1e-6"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: FFT homogenization of a 64 x 64 cell") and "--max-memory-gb" in err[0]
    assert main(args + ["--max-minutes", "0"]) == 2
    assert "--max-minutes" in capsys.readouterr().err
    assert main(args) == 0


def test_recipe_fft_level_refusal_names_the_recipe_keys(monkeypatch):
    """Inside ``nmmm run`` the refusal names the recipe keys that reduce the work, never options of
    fft_permittivity or of ``nmmm homogenize run`` that a recipe does not have."""
    from nmmm.homogenize import work_estimate
    from nmmm.recipes.run import build_materials
    from nmmm.recipes.schema import example_path, load_recipe
    from nmmm.errors import RecipeError

    monkeypatch.setattr(work_estimate, "FFT_MAX_MINUTES", 1e-9)
    recipe = load_recipe(example_path("hematite_coating_fft"))
    with pytest.raises(RecipeError) as info:
        build_materials(recipe)
    msg = str(info.value)
    assert "levels[0].microstructure.size_px (now 32" in msg and "levels[0].fft_step_nm" in msg
    assert "max_minutes=" not in msg and "--single" not in msg and "directions=" not in msg
    with pytest.raises(InvalidInputError, match=r"max_minutes=.*--single.*directions="):
        check_fft_work((64, 64, 64))  # without the caller's advice, the function's own
