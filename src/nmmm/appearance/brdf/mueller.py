"""Mueller matrices of the paint's Fresnel reflections (clear coat, flakes) and Stokes-frame algebra.

The paint BRDF (:class:`~nmmm.appearance.brdf.PaintBRDF`) is unpolarized: each term is the
mean of its s and p parts. Its **polarizing** terms are Fresnel reflections:

- the clear coat's surface reflection (the smooth coat's mirror Dirac, or each GGX microfacet of a
  rough coat, at the microfacet angle θ_d), air → coat;
- each flake's mirror reflection inside the binder, binder → flake (a metal: n + ik; a coherent
  thin-film stack: its ``rs, rp``), preceded and followed by the coat's transmissions
  air → coat and coat → air (diattenuators, no retardance for a dielectric coat).

The diffuse body and the multiple-scattering lobe are treated as **depolarizing** (Mueller
matrix ρ·diag(1, 0, 0, 0)): light scattered many times by pigments loses its polarization.

All matrices come from the Fresnel amplitude coefficients of :func:`nmmm.layers.fresnel`
(``rs``, ``rp``; ``Ts``, ``Tp``) — there is no other Fresnel code here. In the frame whose x axis is
the s direction (perpendicular to the plane of incidence), y = d × x (d the propagation
direction), a reflection is (Collett 2005 eq. 8-26; Mitsuba 3's ``mueller::specular_reflection``)

    M_R = | (Rs+Rp)/2  (Rs−Rp)/2   0     0    |
          | (Rs−Rp)/2  (Rs+Rp)/2   0     0    |
          |     0          0       Re   −Im   |      Re, Im: of rp·rs*
          |     0          0       Im    Re   |

and a transmission M_T = ½ [[Ts+Tp, Ts−Tp, 0, 0], [Ts−Tp, Ts+Tp, 0, 0], [0, 0, 2√(TsTp), 0],
[0, 0, 0, 2√(TsTp)]]. nmmm's ``rp`` has the sign of Mitsuba's ``a_p`` (the "Verdet" convention,
rp = −rs at normal incidence), so for a dielectric (the coat) the two agree element by element. For an
absorbing medium (a metal flake) Mitsuba's ``fresnel_polarized`` returns the complex conjugates of
nmmm's rs, rp (its e^{+iωt} time convention; :func:`nmmm.layers.fresnel` uses e^{−iωt} with n + ik), so
the retardance elements M23, M32 — and the S3 of a metal reflection — have the opposite sign in
Mitsuba; S0, S1, S2 agree (tests/appearance/render/test_mitsuba_polarized.py).

Stokes vectors (S0, S1, S2, S3): S1 = I(x) − I(y), S2 = I(+45°) − I(−45°) in a frame (x, y)
perpendicular to the propagation direction d with (x, y, d) right-handed; S3 = 2 Im(E_y E_x*) with
e^{−iωt} fields: S3 > 0 for a field rotating from x to y (counter-clockwise as seen looking into the
beam). An unpolarized beam reflected once has the degree of
polarization (Rs − Rp)/(Rs + Rp), polarized along s; it is 1 at Brewster's angle of a dielectric.

Public functions
----------------
- :func:`reflection_mueller`, :func:`transmission_mueller` — (…, 4, 4) from r_s, r_p / T_s, T_p.
- :func:`coat_reflection_mueller`, :func:`coat_transmission_mueller` — the clear coat's, per λ.
- :func:`flake_reflection_mueller` — a flake's reflection in the binder, per λ.
- :func:`stokes_rotation` — the rotator that re-expresses a Stokes vector from one x axis to another.
- :func:`degree_of_polarization`, :func:`polarizer_intensity`.

References
----------
- E. Collett, *Field Guide to Polarization*, SPIE (2005); E. Collett, *Polarized Light:
  Fundamentals and Applications*, Marcel Dekker (1993), ch. 8 (Mueller matrices of reflection and
  transmission at a dielectric interface).
- M. Born, E. Wolf, *Principles of Optics*, 7th ed. (1999), §1.5 (Fresnel, Brewster's angle).
- W. Jakob et al., Mitsuba 3 (2022), ``include/mitsuba/render/mueller.h`` (the same frames; S3 of a metal
  reflection has the opposite sign, see above).
"""

from __future__ import annotations

import numpy as np

from nmmm.errors import InvalidInputError

__all__ = [
    "reflection_mueller",
    "transmission_mueller",
    "coat_reflection_mueller",
    "coat_transmission_mueller",
    "flake_reflection_mueller",
    "stokes_rotation",
    "degree_of_polarization",
    "polarizer_intensity",
]


def reflection_mueller(rs, rp) -> np.ndarray:
    """Mueller matrix (…, 4, 4) of a reflection with amplitude coefficients ``rs``, ``rp``
    (complex, broadcast), in the frame whose x axis is s (see the module docstring).

    >>> from nmmm.layers import fresnel
    >>> c = fresnel(1.0, 1.5, 56.309932474020215)  # Brewster's angle of n = 1.5
    >>> M = reflection_mueller(c.rs, c.rp)
    >>> round(float(M[1, 0] / M[0, 0]), 9)  # degree of polarization of unpolarized light
    1.0
    """
    rs = np.asarray(rs, complex)
    rp = np.asarray(rp, complex)
    rs, rp = np.broadcast_arrays(rs, rp)
    Rs, Rp = np.abs(rs) ** 2, np.abs(rp) ** 2
    x = rp * np.conj(rs)
    M = np.zeros(rs.shape + (4, 4))
    M[..., 0, 0] = M[..., 1, 1] = 0.5 * (Rs + Rp)
    M[..., 0, 1] = M[..., 1, 0] = 0.5 * (Rs - Rp)
    M[..., 2, 2] = M[..., 3, 3] = x.real
    M[..., 2, 3] = -x.imag
    M[..., 3, 2] = x.imag
    return M


def transmission_mueller(Ts, Tp) -> np.ndarray:
    """Mueller matrix (…, 4, 4) of a transmission through a dielectric interface with power
    transmittances ``Ts``, ``Tp`` (no retardance), x axis = s."""
    Ts, Tp = np.broadcast_arrays(np.asarray(Ts, float), np.asarray(Tp, float))
    if np.any(Ts < 0) or np.any(Tp < 0):
        raise InvalidInputError("power transmittances Ts, Tp must be >= 0")
    M = np.zeros(Ts.shape + (4, 4))
    M[..., 0, 0] = M[..., 1, 1] = 0.5 * (Ts + Tp)
    M[..., 0, 1] = M[..., 1, 0] = 0.5 * (Ts - Tp)
    M[..., 2, 2] = M[..., 3, 3] = np.sqrt(Ts * Tp)
    return M


def _angle_deg(cos_theta):
    c = np.asarray(cos_theta, float)
    if np.any(~np.isfinite(c)) or np.any(c < -1e-9) or np.any(c > 1 + 1e-9):
        raise InvalidInputError("incidence cosines must lie in [0, 1]")
    return np.minimum(np.degrees(np.arccos(np.clip(c, 0.0, 1.0))), 89.999)


def coat_reflection_mueller(coat, wavelength_nm, cos_theta) -> np.ndarray:
    """The clear coat's surface reflection air → coat at incidence cosines ``cos_theta`` (…):
    Mueller matrices (…, L, 4, 4) on ``wavelength_nm`` (L,), from :func:`nmmm.layers.fresnel`
    with the coat's index n(λ) (:meth:`ClearCoat.index`)."""
    from nmmm.layers import fresnel

    w = np.asarray(wavelength_nm, float).ravel()
    n = coat.index(w)
    th = _angle_deg(cos_theta)[..., None]
    c = fresnel(1.0, n, th)
    return reflection_mueller(c.rs, c.rp)


def coat_transmission_mueller(coat, wavelength_nm, cos_theta, into_coat: bool = True) -> np.ndarray:
    """The clear coat's transmission (…, L, 4, 4): air → coat at incidence cosine ``cos_theta``
    in air (``into_coat``), or coat → air at incidence cosine ``cos_theta`` inside the coat."""
    from nmmm.layers import fresnel

    w = np.asarray(wavelength_nm, float).ravel()
    n = coat.index(w)
    th = _angle_deg(cos_theta)[..., None]
    c = fresnel(1.0, n, th) if into_coat else fresnel(n, 1.0, th)
    return transmission_mueller(np.clip(c.Ts, 0, None), np.clip(c.Tp, 0, None))


def flake_reflection_mueller(optics, wavelength_nm, cos_local, n_binder: float) -> np.ndarray:
    """A flake's mirror reflection in the binder (index ``n_binder``) at local incidence cosines
    ``cos_local`` (…): Mueller matrices (…, L, 4, 4).

    A :class:`~nmmm.appearance.flakes.MetalFlakeOptics` uses :func:`nmmm.layers.fresnel`
    binder → metal (n + ik: the metal's retardance turns linear into elliptical polarization); a
    :class:`~nmmm.appearance.flakes.ThinFilmFlakeOptics` the ``rs, rp`` of its
    :class:`nmmm.layers.Stack` when every layer is coherent; with an incoherent layer (the mica)
    only ``Rs, Rp`` are known and the matrix is taken without retardance (c = √(Rs Rp), δ = 0).
    """
    from nmmm.appearance.flakes import MetalFlakeOptics, ThinFilmFlakeOptics
    from nmmm.layers import Stack, fresnel
    from nmmm.materials import as_material

    w = np.asarray(wavelength_nm, float).ravel()
    th = _angle_deg(cos_local)
    if isinstance(optics, MetalFlakeOptics):
        nk = np.asarray(as_material(optics.material).nk(w), complex)
        c = fresnel(float(n_binder), nk, th[..., None])
        return reflection_mueller(c.rs, c.rp)
    if isinstance(optics, ThinFilmFlakeOptics):
        res = Stack(list(optics.layers), ambient=float(n_binder), substrate=float(n_binder)).rt(w, th.ravel())
        if getattr(res, "rs", None) is not None and getattr(res, "rp", None) is not None:
            rs = np.moveaxis(np.asarray(res.rs), -1, 0).reshape(th.shape + (w.size,))
            rp = np.moveaxis(np.asarray(res.rp), -1, 0).reshape(th.shape + (w.size,))
            return reflection_mueller(rs, rp)
        Rs = np.moveaxis(np.asarray(res.Rs, float), -1, 0).reshape(th.shape + (w.size,))
        Rp = np.moveaxis(np.asarray(res.Rp, float), -1, 0).reshape(th.shape + (w.size,))
        return reflection_mueller(np.sqrt(Rs), np.sqrt(Rp))
    raise InvalidInputError(f"no Mueller matrix for flake optics {type(optics).__name__}: "
                            "use MetalFlakeOptics or ThinFilmFlakeOptics")


def stokes_rotation(from_axis, to_axis, direction) -> np.ndarray:
    """Rotator (…, 4, 4) re-expressing a Stokes vector given with x axis ``from_axis`` in the
    frame with x axis ``to_axis``, both perpendicular to the propagation ``direction`` (…, 3)
    (y = d × x in both frames). With ψ the angle of ``from_axis`` in the new frame,
    S1' = S1 cos 2ψ − S2 sin 2ψ, S2' = S1 sin 2ψ + S2 cos 2ψ."""
    a = np.asarray(from_axis, float)
    b = np.asarray(to_axis, float)
    d = np.asarray(direction, float)
    psi = np.arctan2(np.einsum("...k,...k->...", a, np.cross(d, b)), np.einsum("...k,...k->...", a, b))
    c, s = np.cos(2 * psi), np.sin(2 * psi)
    R = np.zeros(psi.shape + (4, 4))
    R[..., 0, 0] = R[..., 3, 3] = 1.0
    R[..., 1, 1] = R[..., 2, 2] = c
    R[..., 1, 2] = -s
    R[..., 2, 1] = s
    return R


def degree_of_polarization(stokes, linear: bool = False) -> np.ndarray:
    """√(S1² + S2² (+ S3²)) / S0 of Stokes vectors (…, 4) (0 where S0 = 0)."""
    S = np.asarray(stokes, float)
    p = np.sqrt(S[..., 1] ** 2 + S[..., 2] ** 2 + (0 if linear else S[..., 3] ** 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(S[..., 0] > 0, p / np.where(S[..., 0] > 0, S[..., 0], 1.0), 0.0)


def polarizer_intensity(stokes, angle_deg) -> np.ndarray:
    """Intensity behind an ideal linear polarizer whose transmission axis is at ``angle_deg``
    from the frame's x axis towards y: ½ (S0 + S1 cos 2α + S2 sin 2α), for Stokes (…, 4)."""
    S = np.asarray(stokes, float)
    a = np.radians(float(angle_deg))
    return 0.5 * (S[..., 0] + S[..., 1] * np.cos(2 * a) + S[..., 2] * np.sin(2 * a))
