"""The threaded and the serial Mie batch kernels keep separate on-disk Numba cache entries.

Numba names a cache entry by module, qualified name, first line and signature, not by
``parallel=``: when both builds were made from the same function they shared one index file,
and whichever compiled first served both, so a small (serial) call on a fresh cache left every
later large batch on one thread (the same defect was measured in homogenize's kernels, issue 22).
"""

import numpy as np

from nmmm.layers import mie
from nmmm.layers import mie_scattering as ms


def test_parallel_and_serial_builds_have_their_own_cache_entries():
    par = ms._mie_batch._cache._cache_file._index_name
    ser = ms._mie_batch_serial._cache._cache_file._index_name
    assert par != ser, (par, ser)


def test_serial_and_parallel_paths_agree(monkeypatch):
    d = np.linspace(50.0, 900.0, 400)
    w = np.linspace(400.0, 700.0, 61)[:, None]
    ref = mie(1.8 + 0.01j, 1.5, d, w)
    monkeypatch.setattr(ms, "PARALLEL_ABOVE_TERMS", 10**12)  # force the serial kernel
    ser = mie(1.8 + 0.01j, 1.5, d, w)
    np.testing.assert_array_equal(ser.qext, ref.qext)
    np.testing.assert_array_equal(ser.g, ref.g)
