"""Spectral batches on Dask: the chunked spectrum equals the one-process spectrum."""


import numpy as np
import pytest

from nmmm.errors import InvalidInputError
from nmmm.homogenize import fft_permittivity, fft_permittivity_spectrum
from nmmm.homogenize import geometries as G

distributed = pytest.importorskip("dask.distributed")


def test_chunks_reproduce_the_serial_spectrum(client):
    lab = G.boolean_spheres(16, 0.2, 2.5, ndim=3, seed=2)
    eps_m = np.linspace(-50 + 20j, -10 + 2j, 7)
    eps = {0: 2.25, 1: eps_m}
    ref = fft_permittivity(lab, eps, tol=1e-8)
    r = fft_permittivity_spectrum(lab, eps, client=client, tol=1e-8)
    assert r.tensor.shape == ref.tensor.shape == (7, 3, 3)
    assert np.abs(r.tensor - ref.tensor).max() <= 1e-6 * np.abs(ref.tensor).max()
    assert r.iterations.shape == (7, 3) and len(r.residual_history) == 7
    # a two-phase spectrum is one Lanczos run per loading: whole loadings go to the 2 tasks in turn
    assert r.metadata["method"] == ref.metadata["method"] == "lanczos"
    assert [c[:2] for c in r.metadata["chunks"]] == [(0, 7), (0, 7)]
    assert r.metadata["chunk_loadings"] == [(0, 2), (1,)]
    assert r.green == ref.green and r.switches == ref.switches


def test_every_chunk_takes_the_whole_spectrum_choice(client):
    """A low-loss metal at one end of the spectrum only: both chunks use the operator the whole
    spectrum asks for (no jump of ε_eff at the chunk boundary)."""
    lab = G.boolean_spheres(16, 0.2, 2.5, ndim=3, seed=2)
    eps_m = np.array([-50 + 20j, -45 + 18j, -40 + 15j, -50 + 2j])  # only the last is low-loss
    r = fft_permittivity_spectrum(lab, {0: 2.25, 1: eps_m}, client=client, n_chunks=2, directions=[0])
    ref = fft_permittivity(lab, {0: 2.25, 1: eps_m}, directions=[0])
    assert r.green == ref.green == "willot2014"
    assert set(r.metadata["green_used"].ravel()) == {"willot2014"}
    assert np.abs(r.tensor[:, 0, 0] - ref.tensor[:, 0, 0]).max() <= 1e-4 * np.abs(ref.tensor[:, 0, 0]).max()


def test_refuses_a_single_wavelength_and_fields(client):
    lab = G.boolean_spheres(8, 0.2, 2.0, ndim=3, seed=2)
    with pytest.raises(InvalidInputError, match="over wavelength"):
        fft_permittivity_spectrum(lab, {0: 2.25, 1: -50 + 20j}, client=client)
    with pytest.raises(InvalidInputError, match="return_fields"):
        fft_permittivity_spectrum(lab, {0: 2.25, 1: np.array([-50 + 20j, -40 + 5j])}, client=client,
                                  return_fields=True)


def test_worker_warnings_and_errors_reach_the_caller():
    """A worker's warnings (here: the cell is not periodic) are warned in the caller once, not left in
    the worker's log; a worker's error is raised in the caller with its chunk named (review Q). The
    default local cluster of worker processes, closed afterwards."""
    x, y, z = np.indices((12, 12, 12))
    lab = ((x - 6) ** 2 + (y - 6) ** 2 + z ** 2 < 25).astype(int)  # a sphere cut by the z seam, not wrapped
    eps = {0: 2.25, 1: np.linspace(-20 + 5j, -10 + 2j, 4)}
    from nmmm.homogenize.validity import PeriodicityWarning

    with pytest.warns(PeriodicityWarning, match="does not look periodic") as rec:
        r = fft_permittivity_spectrum(lab, eps, directions=[0], n_workers=2)
    assert len([w for w in rec if issubclass(w.category, PeriodicityWarning)]) == 1
    assert r.tensor.shape == (4, 3, 3)
    from nmmm.errors import ConvergenceError

    with pytest.raises(ConvergenceError) as exc:  # its "wavelength index" counts within the chunk: named
        fft_permittivity_spectrum(lab, eps, directions=[0], n_workers=2, maxiter=1, fallback=False)
    assert any("in the Dask task of wavelengths" in n for n in getattr(exc.value, "__notes__", []))
