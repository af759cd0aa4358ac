"""How fft_permittivity_spectrum cuts a spectrum into Dask tasks (issue 22).

- :func:`wavelength_work` against the projections the solver actually takes (cold solves, so that
  every wavelength is measured alone).
- The plan covers every (wavelength, loading) solve once; per-wavelength pieces carry equal
  estimated work; Lanczos runs keep whole loadings.
- A per-wavelength spectrum cut inside a loading equals the one-process spectrum.
"""

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from nmmm.homogenize import fft_permittivity, fft_permittivity_spectrum
from nmmm.homogenize import geometries as G
from nmmm.homogenize.spectral_batches import _plan, wavelength_work

def _aluminium(nwl=6):
    """Aluminium (Rakić) at nwl wavelengths 380-780 nm, as benchmarks/bench_fft_metals.py uses it."""
    import nmmm.materials as M

    return M.get("main/Al/Rakic").eps(np.linspace(380.0, 780.0, nwl))


EPS_AL = _aluminium()


def _flakes(n=24):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
    from bench_fft_metals import flakes

    return flakes(n)


def _cold_projections(lab, eps_m):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # the residual rule, on which wavelength_work was measured (the flux rule's counts spread 1.35× more)
        r = fft_permittivity(lab, {0: 2.25, 1: eps_m}, method="per_wavelength", warm_start=False, directions=[0],
                             tol=1e-5, progress=False, stop="residual")
    return r.iterations[:, 0].astype(float)


def test_wavelength_work_follows_the_projections_of_metal_flakes():
    """Flakes (the issue's aluminium case): projections / estimated work constant within 30 %
    (measured 26-30 at 24³), where the projections themselves vary 3×; for Boolean spheres the
    estimate ranks the wavelengths as the projections do (it overstates the spread: 2.9× vs 2×)."""
    table = np.stack([np.full(EPS_AL.size, 2.25 + 0j), EPS_AL], axis=1)
    work = wavelength_work(table)
    its = _cold_projections(_flakes(), EPS_AL)
    assert its.max() / its.min() > 2.0
    ratio = its / work
    assert ratio.max() / ratio.min() <= 1.3
    its_s = _cold_projections(G.boolean_spheres(24, 0.2, 3.0, ndim=3, seed=1), EPS_AL)
    assert list(np.argsort(-its_s)) == list(np.argsort(-work))


def test_wavelength_work_of_dielectrics_is_the_root_of_the_contrast():
    work = wavelength_work([[2.25, 9.0], [2.25, 2.25 * 16]])
    np.testing.assert_allclose(work, [2.0, 4.0])


@pytest.mark.parametrize("n_dirs,k", [(3, 2), (3, 4), (1, 2), (2, 5), (3, 48)])
def test_plan_covers_every_solve_once_with_equal_work(n_dirs, k):
    nw = 16
    work = np.linspace(5.3, 1.75, nw)
    pieces = _plan(work, n_dirs, k, whole_loadings=False)
    assert len(pieces) == min(k, nw * n_dirs)
    seen = np.zeros((nw, n_dirs), int)
    loads = []
    for segs in pieces:
        load = 0.0
        for lo, hi, cs in segs:
            assert 0 <= lo < hi <= nw
            for c in cs:
                seen[lo:hi, c] += 1
                load += work[lo:hi].sum() + (work[0] * (1 / 0.6 - 1) if lo == 0 else 0.0)
        loads.append(load)
    assert (seen == 1).all()
    # contiguous cut of a line of items: each piece within one (largest) item of the mean
    assert max(loads) - min(loads) <= 2 * work[0] / 0.6 + 1e-9


def test_plan_keeps_lanczos_loadings_whole():
    pieces = _plan(np.linspace(5, 2, 8), 3, 2, whole_loadings=True)
    assert pieces == [[(0, 8, (0, 2))], [(0, 8, (1,))]]


@pytest.mark.parametrize("n_dirs,k", [(3, 4), (2, 3), (1, 8)])
def test_plan_gives_lanczos_loadings_whole_with_more_tasks_than_loadings(n_dirs, k):
    """More tasks than loadings: one loading per piece, never a loading cut over wavelengths (two
    Lanczos runs in one task, each as long as its slowest wavelength)."""
    pieces = _plan(np.linspace(5, 2, 8), n_dirs, k, whole_loadings=True)
    assert pieces == [[(0, 8, (c,))] for c in range(n_dirs)]


def test_per_wavelength_spectrum_cut_inside_a_loading_equals_one_process(client):
    lab = _flakes(16)
    eps = {0: 2.25, 1: EPS_AL}
    kw = dict(method="per_wavelength", tol=1e-8)
    ref = fft_permittivity(lab, eps, progress=False, **kw)
    r = fft_permittivity_spectrum(lab, eps, client=client, n_chunks=2, **kw)
    chunks = r.metadata["chunks"]
    assert len(r.metadata["tasks"]) == 2
    # 3 loadings × 6 wavelengths in two pieces of equal work: the cut falls inside the middle loading
    assert r.metadata["chunk_loadings"] == [(0,), (1,), (1,), (2,)]
    assert chunks[1][:2] == (0, chunks[2][0]) and chunks[2][1] == 6
    assert r.tensor.shape == ref.tensor.shape == (6, 3, 3)
    assert np.abs(r.tensor - ref.tensor).max() <= 1e-6 * np.abs(ref.tensor).max()
    assert r.iterations.shape == (6, 3) and len(r.residual_history) == 6
    assert all(len(h) == 3 for h in r.residual_history)
    # warm starts everywhere but at each piece's first wavelength: the cold start at the cut costs more
    c = chunks[2][0]
    assert r.iterations[c, 1] >= ref.iterations[c, 1]
    assert (r.iterations[:, [0, 2]] == ref.iterations[:, [0, 2]]).all()
    assert r.switches == ref.switches and r.green == ref.green


@pytest.mark.parametrize("n_chunks", [0, -1, 2.5, True])
def test_n_chunks_must_be_a_positive_integer(n_chunks):
    """Refused before any cluster starts (0 was taken as 'one per worker', -1 as one task, 2.5 as 2)."""
    from nmmm.errors import InvalidInputError
    from nmmm.homogenize.spectral_batches import fft_permittivity_spectrum

    lab = np.zeros((8, 8, 8), np.uint8)
    lab[:4] = 1
    with pytest.raises(InvalidInputError, match="n_chunks"):
        fft_permittivity_spectrum(lab, {0: np.full(3, 2.25), 1: np.full(3, -20 + 4j)}, n_chunks=n_chunks,
                                  client=object())
