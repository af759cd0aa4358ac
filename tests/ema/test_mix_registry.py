"""Dispatcher, Material-valued mixtures across levels, causality, the gold-ruby example."""

import warnings

import numpy as np
import pytest

from nmmm.ema import (
    EFFECTIVE_PERMITTIVITY_METHODS,
    Inclusion,
    Shape,
    SizeValidityWarning,
    bruggeman,
    effective_permittivity,
    maxwell_garnett,
    maxwell_garnett_ellipsoid,
    mix,
    mix_tensor,
)
from nmmm.errors import InvalidInputError, OutOfRangeError
from nmmm.materials import Material, TabulatedMaterial


def test_dispatcher_names_and_aliases():
    ei, em, f = -4 + 0.7j, 2.25, 0.2
    assert effective_permittivity(ei, em, f) == maxwell_garnett(ei, em, f)
    for name in ("bruggeman", "Bruggeman", "EMA"):
        np.testing.assert_allclose(effective_permittivity(ei, em, f, method=name), bruggeman(ei, em, f))
    np.testing.assert_allclose(
        effective_permittivity(ei, em, f, method="maxwell-garnett ellipsoid", depolarization=[0.2, 0.2, 0.6]),
        maxwell_garnett_ellipsoid(ei, em, f, [0.2, 0.2, 0.6]))
    np.testing.assert_allclose(effective_permittivity(ei, em, f, method="parallel"), f * ei + (1 - f) * em)
    for key in EFFECTIVE_PERMITTIVITY_METHODS:
        if key not in ("maxwell_garnett_ellipsoid", "maxwell_garnett_shape", "maxwell_garnett_mie"):
            assert np.isclose(effective_permittivity(ei, em, 0.0, method=key), em)
    with pytest.raises(InvalidInputError, match="unknown effective-medium method"):
        effective_permittivity(ei, em, f, method="magic")
    # an option the method does not take is named, with the ones it does take
    with pytest.raises(InvalidInputError, match=r"'bruggeman' takes no argument\(s\) \['depolarization'\].*shapes"):
        effective_permittivity(ei, em, f, method="bruggeman", depolarization=[0.2, 0.2, 0.6])


def test_mix_is_a_material_and_matches_the_formula(gold_silica):
    w, au, si, ea, es = gold_silica
    glass = mix(si, [Inclusion(au, 0.0005)])
    assert isinstance(glass, Material)
    np.testing.assert_allclose(glass.eps(w), maxwell_garnett(ea, es, 0.0005), rtol=1e-12)
    assert glass.range_nm == (max(au.range_nm[0], si.range_nm[0]), min(au.range_nm[1], si.range_nm[1]))
    with pytest.raises(OutOfRangeError):
        glass.nk([5000.0])
    br = mix(si, [(au, 0.3)], method="bruggeman")
    np.testing.assert_allclose(br.eps(w), bruggeman(ea, es, 0.3), rtol=1e-10)


def test_mix_takes_database_keys_and_refuses_disjoint_ranges(gold_silica):
    w, au, si, ea, es = gold_silica
    by_key = mix("main/SiO2/Malitson", [("main/Au/Johnson", 0.0005)])
    np.testing.assert_allclose(by_key.eps(w), maxwell_garnett(ea, es, 0.0005), rtol=1e-12)
    blue = TabulatedMaterial("blue only", [400.0, 500.0], [1.5, 1.5], [0.0, 0.0])
    red = TabulatedMaterial("red only", [600.0, 700.0], [2.0, 2.0], [0.1, 0.1])
    with pytest.raises(OutOfRangeError, match="do not overlap"):
        mix(blue, [(red, 0.1)])
    with pytest.raises(OutOfRangeError, match="do not overlap"):
        mix_tensor(blue, [Inclusion(red, 0.1, Shape.spheroid(2.0, orientation="aligned"))])


def test_gold_ruby_plasmon_peak_between_520_and_535_nm(gold_silica):
    """The seed's Figure 1: the absorption band of gold spheres in silica (p = 0.0005)."""
    w, au, si, _, _ = gold_silica
    k = mix(si, [Inclusion(au, 0.0005)]).k(w)
    peak = w[np.argmax(k)]
    assert 520 <= peak <= 535


def test_nested_levels_equal_explicit_formula_composition():
    w = np.linspace(400, 700, 31)
    pig = TabulatedMaterial("pigment", w, np.full(w.size, 2.8), np.linspace(0.6, 0.05, w.size))
    binder = TabulatedMaterial("binder", w, np.full(w.size, 1.55), np.full(w.size, 1e-4))
    aggregate = mix(binder, [Inclusion(pig, 0.4, Shape.cube())])
    layer = mix(binder, [Inclusion(aggregate, 0.2)], method="bruggeman")
    e_agg = maxwell_garnett(pig.eps(w), binder.eps(w), 0.4)  # sphere reference
    assert not np.allclose(aggregate.eps(w), e_agg)  # the cube approximation is not a sphere
    from nmmm.ema import maxwell_garnett_shape

    e_agg = maxwell_garnett_shape(pig.eps(w), binder.eps(w), 0.4, Shape.cube())
    np.testing.assert_allclose(layer.eps(w), bruggeman(e_agg, binder.eps(w), 0.2), rtol=1e-10)
    assert layer.components[1] is aggregate and layer.metadata["method"] == "bruggeman"


def test_mix_tensor_and_random_orientation():
    w = np.linspace(400, 700, 7)
    L = Shape.spheroid(3.0, orientation="aligned")
    o, o2, e = mix_tensor(1.5, [Inclusion(0.2 + 3j, 0.01, L)])
    np.testing.assert_allclose(o.eps(w), o2.eps(w))
    ref = maxwell_garnett_ellipsoid((0.2 + 3j) ** 2, 2.25, 0.01, L.depolarization, orientation="aligned")
    np.testing.assert_allclose(e.eps(w), np.full(w.size, ref[2]), rtol=1e-12)
    with pytest.raises(InvalidInputError, match="mix_tensor"):
        mix(1.5, [Inclusion(0.2 + 3j, 0.01, L)])


def test_mix_size_warnings_and_errors():
    w = np.linspace(400, 700, 7)
    big = mix(1.5, [Inclusion(0.2 + 3j, 0.01, radius_nm=60.0)])
    with pytest.warns(SizeValidityWarning, match="maxwell_garnett_mie"):
        big.eps(w)
    small = mix(1.5, [Inclusion(0.2 + 3j, 0.01, radius_nm=5.0)])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        small.eps(w)
    with pytest.raises(InvalidInputError, match="radius_nm"):
        mix(1.5, [Inclusion(0.2 + 3j, 0.01)], method="maxwell_garnett_mie")
    with pytest.raises(InvalidInputError, match="> 1"):
        mix(1.5, [(2.0, 0.6), (2.5, 0.6)])
    with pytest.raises(InvalidInputError):
        Inclusion(2.0, 1.5)
    with pytest.raises(InvalidInputError):
        mix(1.5, [(2.0, 0.1, Shape.cube())], method="looyenga")


def test_mixture_is_causal_and_decoupled_model_is_not(gold_silica):
    """Kramers–Kronig (nmmm.materials.kramers_kronig): the index change of the composite follows
    from its absorption change; keeping silica's n with the composite's k does not."""
    from nmmm.ema.causality import kk_check_mixture, kk_index_change

    _, au, si, _, _ = gold_silica
    glass = mix(si, [Inclusion(au, 0.01)])
    change = kk_index_change(glass, si)
    assert change.relative_error < 0.1
    reports = kk_check_mixture(glass, si, n_points=800)
    assert reports["decoupled"].max_abs > 5 * reports["mixture"].max_abs


def test_mix_bruggeman_with_rods_matches_formula():
    from nmmm.ema import bruggeman

    w = np.linspace(400, 700, 7)
    rods = Shape.spheroid(3.0)
    m = mix(1.5, [Inclusion(0.2 + 3j, 0.2, rods)], method="bruggeman")
    ref = bruggeman((0.2 + 3j) ** 2, 2.25, 0.2, shapes=[rods, None])
    np.testing.assert_allclose(m.eps(w), np.full(w.size, ref), rtol=1e-12)
