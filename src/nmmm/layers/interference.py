"""Interference (pearlescent) pigments: TiO2-coated mica platelets in a binder.

A mica platelet (a few hundred nm thick) coated on both faces with a thin TiO2 layer
reflects a colour set by the optical thickness of the TiO2 (the seed paper's fourth
example). The platelet lies parallel to the film surface; seen at specular geometry its
reflectance is that of the layer stack

    air | binder (thick, incoherent) | TiO2 | mica | TiO2 | binder (semi-infinite)

The mica is treated as incoherent by default: its thickness varies from platelet to
platelet by much more than a wavelength/(2n), which averages its own fringes out
(Maile, Pfaff & Reynders 2005, §3; Pfaff 2008, ch. 3). The binder under the platelet is
semi-infinite, i.e. the film lies over a black background (how pearl pigments are judged).

Public functions
----------------
- :func:`muscovite` — a Cauchy model of muscovite mica, ``n(589 nm) = 1.58``.
- :func:`platelet_stack` — the :class:`~nmmm.layers.thinfilm.Stack` above.
- :func:`platelet_reflectance` — reflectance spectra against TiO2 thickness and angle.
- :func:`interference_colours` — CIELAB (D65) and sRGB of those spectra.

The worked example (spectra and sRGB swatches against TiO2 thickness) is
:func:`nmmm.demo.interference.demo`.

References
----------
- F. J. Maile, G. Pfaff, P. Reynders, "Effect pigments — past, present and future",
  Prog. Org. Coat. 54, 150–163 (2005). doi:10.1016/j.porgcoat.2005.07.003
- G. Pfaff, *Special Effect Pigments*, 2nd ed., Vincentz Network (2008), ch. 3.
- W. A. Deer, R. A. Howie, J. Zussman, *An Introduction to the Rock-Forming Minerals*,
  2nd ed., Longman (1992) — muscovite: n_alpha 1.552–1.576, n_beta 1.582–1.615,
  n_gamma 1.587–1.618.
- A. Jolivet et al., "Structural, optical, and electrical properties of TiO2 thin films
  deposited by ALD", Appl. Surf. Sci. 608, 155214 (2023) — anatase n, k
  (refractiveindex.info ``main/TiO2/Jolivet-anatase``).
- H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press (2010), §3.2 — quarter-
  wave maxima of a high-index film, ``lambda_max = 4 n d / (2m + 1)``.
"""

from __future__ import annotations

from typing import Any

from nmmm.errors import InvalidInputError
from nmmm.layers.thinfilm import Layer, Stack
from nmmm.spectra import check_positive

__all__ = [
    "DEFAULT_TIO2",
    "muscovite",
    "platelet_stack",
    "platelet_reflectance",
    "interference_colours",
]

#: refractiveindex.info key of the default TiO2 (anatase, as on most pearl pigments)
DEFAULT_TIO2 = "main/TiO2/Jolivet-anatase"

#: default binder index (a clear acrylic / epoxy resin; any Material may be given instead)
DEFAULT_BINDER_N = 1.50


def muscovite():
    """Muscovite mica as a non-absorbing Cauchy material, ``n(589.3 nm) = 1.580``.

    ``n(λ) = A + B/λ²`` (λ in µm) with ``A = 1.5685`` and ``B = 0.0040 µm²``. The value
    1.58 is the index used for mica in the pearl-pigment literature (Maile et al. 2005;
    Pfaff 2008) and lies inside muscovite's n_beta–n_gamma range (1.582–1.618) seen at
    near-normal incidence on the cleavage plane (Deer, Howie & Zussman 1992). The
    dispersion term B is an assumption (that of a crown glass, ~0.004 µm²): no tabulated
    n(λ) of mica is in the database. Birefringence (~0.005 in the plane) is neglected.
    """
    from nmmm.materials import Cauchy

    return Cauchy(
        A=1.5685,
        B=0.0040,
        name="muscovite mica (Cauchy, n_D = 1.58)",
        reference=(
            "n_D = 1.58: Maile, Pfaff, Reynders, Prog. Org. Coat. 54, 150 (2005); Deer, Howie, Zussman "
            "(1992); Cauchy B = 0.004 um^2 assumed (crown-glass-like dispersion)"
        ),
    )


def _tio2(tio2):
    if tio2 is None:
        from nmmm.materials import get

        return get(DEFAULT_TIO2)
    if isinstance(tio2, str):
        from nmmm.materials import get

        return get(tio2)
    return tio2


def platelet_stack(
    tio2_thickness_nm,
    mica_thickness_nm: float = 400.0,
    *,
    tio2: Any = None,
    mica: Any = None,
    binder: Any = DEFAULT_BINDER_N,
    binder_thickness_nm: float | None = 20_000.0,
    mica_coherent: bool = False,
) -> Stack:
    """The layer stack of a TiO2/mica/TiO2 platelet lying flat in a binder film.

    Parameters
    ----------
    tio2_thickness_nm : float or ndarray
        Thickness of each TiO2 coating (nm, > 0); an array gives a thickness series
        (results gain its axes in front of wavelength and angle).
    mica_thickness_nm : float
        Mica substrate thickness (typical 200–500 nm).
    tio2, mica, binder : Material, key or complex
        Defaults: :data:`DEFAULT_TIO2` from the database, :func:`muscovite`, n = 1.50.
    binder_thickness_nm : float or None
        Binder above the platelet, incoherent (a film of tens of µm). ``None`` puts the
        platelet directly in a semi-infinite binder ambient (its reflectance inside the
        film, without the air/binder surface).
    mica_coherent : bool
        Treat the mica as coherent (a single, exactly flat platelet) instead of
        incoherent (default; see the module notes).
    """
    d = check_positive(tio2_thickness_nm, "tio2_thickness_nm")
    check_positive(mica_thickness_nm, "mica_thickness_nm")
    t = _tio2(tio2)
    m = muscovite() if mica is None else mica
    layers = [Layer(t, d), Layer(m, mica_thickness_nm, coherent=mica_coherent), Layer(t, d)]
    if binder_thickness_nm is None:
        return Stack(layers, ambient=binder, substrate=binder)
    return Stack([Layer(binder, binder_thickness_nm, coherent=False)] + layers, ambient=1.0, substrate=binder)


def platelet_reflectance(tio2_thickness_nm, wavelength_nm, angle_deg=0.0, **stack_kwargs):
    """Unpolarized specular reflectance of the platelet film (see :func:`platelet_stack`).

    Returns an array of shape ``tio2_thickness.shape + wavelength.shape + angle.shape``.
    ``angle_deg`` is the angle of incidence in air (or in the binder when
    ``binder_thickness_nm=None``).
    """
    return platelet_stack(tio2_thickness_nm, **stack_kwargs).rt(wavelength_nm, angle_deg).R


def interference_colours(wavelength_nm, reflectance, illuminant: str = "D65"):
    """CIELAB and encoded sRGB of reflectance spectra (last axis = wavelength).

    Uses :mod:`nmmm.colour` (CIE 1931 2° observer, explicit illuminant).
    Returns ``(lab, srgb)`` with shapes ``reflectance.shape[:-1] + (3,)``.
    """
    from nmmm.colour import spectra_to_lab, spectra_to_srgb

    lab = spectra_to_lab(wavelength_nm, reflectance, illuminant=illuminant)
    srgb = spectra_to_srgb(wavelength_nm, reflectance, illuminant=illuminant)
    return lab, srgb


def _check_thickness_series(d):  # pragma: no cover - kept for API symmetry
    d = check_positive(d, "tio2_thickness_nm")
    if d.ndim > 1:
        raise InvalidInputError("give a 1-D series of TiO2 thicknesses")
    return d
