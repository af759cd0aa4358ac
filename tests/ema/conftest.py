import numpy as np
import pytest


@pytest.fixture(scope="session")
def gold_silica():
    """Johnson & Christy gold and Malitson silica on 300–1000 nm (1 nm)."""
    import nmmm.materials as M

    w = np.arange(300.0, 1001.0, 1.0)
    au, si = M.get("main/Au/Johnson"), M.get("main/SiO2/Malitson")
    return w, au, si, au.eps(w), si.eps(w)


def random_eps(rng, size, lossy=True):
    """Random permittivities in the closed upper half plane, moduli 0.1–100."""
    mag = 10 ** rng.uniform(-1, 2, size)
    ph = rng.uniform(0.0 if not lossy else 1e-3, np.pi - (1e-3 if lossy else 0.0), size)
    return mag * np.exp(1j * ph)
