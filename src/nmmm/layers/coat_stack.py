"""Stacks of coats (clear coat, basecoats, primer) on a substrate, by adding–doubling through
the whole stack with the index mismatch handled at every interface — and by Kubelka–Munk +
Saunderson where it applies.

Public functions and classes
----------------------------
- :class:`Coat` — one coat: name, thickness, binder, components (frozen dataclass).
- :class:`Substrate` — below the stack: a Lambertian reflectance (number or spectrum), a
  compound (metal or dielectric, n + ik: Fresnel reflection), ``"black"`` or ``"white"``.
- :class:`CoatStack` — coats top first, on a substrate, under an ambient.
- :func:`stack_reflectance` — the spectrum as an instrument reports it (``geometry``, registry
  :data:`GEOMETRIES` in :mod:`nmmm.layers.geometries`), ``solver="ad"`` or ``"km"``.
- :func:`stack_adding_doubling` — the kernel: slabs given by albedo, optical thickness, phase
  moments and index, top first.

Method
------
Every medium shares one set of angular nodes in u = n² sin²θ (Snell's invariant,
:func:`nmmm.layers.adding_doubling_method.snell_quadrature`) with the squared indices of the
ambient and of all coats as break points: a node refracts into the same node in every medium,
so the Fresnel interfaces are diagonal. The state is the flux per node (radiance × 2ν w, with
2ν dν = du/n²), in which an interface is R(u) and T(u) = 1 − R(u), and a node beyond a
medium's own index (u ≥ n²) carries nothing in it (total internal reflection on the denser
side). Each homogeneous coat is doubled (Wiscombe's diamond start, δ-M truncation at its own
node count) on its propagating nodes; coats, interfaces and substrate are combined with the
adding equations (Prahl 1995, eqs. 5.18–5.21, for asymmetric layers):

    R⁺ = R_a⁺ + T_a⁻ R_b⁺ (I − R_a⁻ R_b⁺)⁻¹ T_a⁺ ,   T⁺ = T_b⁺ (I − R_a⁻ R_b⁺)⁻¹ T_a⁺

The substrate: a Lambertian reflector ρ (flux into node i: ρ · du_i/n²), or a Fresnel
interface with a compound n + ik (light not reflected is absorbed, or for a real index counted
as transmittance).

KM path: each coat's K, S from Gate's (1974) mapping, coats combined by Kubelka's (1954)
layered-system formula R_12 = R_1 + T_1² R_2 /(1 − R_1 R_2) (diffuse fluxes), Saunderson's
correction at the top surface only (the index mismatch between coats is ignored: the KM path
is for index-matched coats; :func:`stack_reflectance` reports AD − KM when asked).

References
----------
- S. A. Prahl, "The adding-doubling method" (1995), in Welch & van Gemert (eds.), ch. 5.
- W. J. Wiscombe, J. Quant. Spectrosc. Radiat. Transfer 16, 637 (1976).
- P. Kubelka, "New contributions to the optics of intensely light-scattering materials.
  Part II: Nonhomogeneous layers", J. Opt. Soc. Am. 44, 330 (1954). doi:10.1364/JOSA.44.000330
- J. L. Saunderson, J. Opt. Soc. Am. 32, 727 (1942).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from nmmm.errors import InvalidInputError
from nmmm.layers.adding_doubling_method import AD_AUTO_QUAD_PTS, _slab, auto_quad_pts, snell_quadrature
from nmmm.layers.fresnel_equations import fresnel, medium_nk
from nmmm.layers.pigment_mixture import Component, MixtureOptics, check_cpvc, mixture_optics
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = ["Coat", "Substrate", "CoatStack", "StackReflectance", "StackADResult", "coat_optics",
           "stack_adding_doubling", "stack_reflectance", "STACK_SOLVERS"]


@dataclass(frozen=True)
class Coat:
    """One coat: ``thickness_nm`` (> 0, ``np.inf`` for opaque), ``binder`` (Material or
    complex), ``components`` (:class:`~nmmm.layers.pigment_mixture.Component`, none for a clear
    coat), ``cpvc`` and ``dependent_scattering`` as in
    :func:`~nmmm.layers.pigment_mixture.mixture_optics`."""

    name: str
    thickness_nm: float
    binder: object
    components: tuple = ()
    dependent_scattering: bool = False
    cpvc: float | None = None

    def __post_init__(self):
        try:
            t = float(self.thickness_nm)
        except (TypeError, ValueError):
            t = np.nan
        if not t > 0:
            raise InvalidInputError(f"coat {self.name!r}: thickness_nm must be > 0 (np.inf for an opaque coat), "
                                    f"got {self.thickness_nm!r}")
        object.__setattr__(self, "components", tuple(self.components))
        if self.cpvc is not None:
            check_cpvc(self.cpvc, f"coat {self.name!r}: cpvc")
        for c in self.components:
            if not isinstance(c, Component):
                raise InvalidInputError(f"coat {self.name!r}: components must be nmmm.layers.pigment_mixture.Component")

    def with_thickness(self, thickness_nm: float) -> "Coat":
        return Coat(self.name, thickness_nm, self.binder, self.components, self.dependent_scattering, self.cpvc)


@dataclass(frozen=True)
class Substrate:
    """Below the stack: ``reflectance`` (Lambertian, number or spectrum in [0, 1]) or
    ``compound`` (n + ik, Fresnel). ``Substrate.black()``, ``Substrate.white()``."""

    reflectance: object = None
    compound: object = None

    def __post_init__(self):
        if (self.reflectance is None) == (self.compound is None):
            raise InvalidInputError("a substrate is either a reflectance (Lambertian) or a compound (n + ik), not both/neither")
        if self.reflectance is not None:
            rho = check_finite(self.reflectance, "substrate reflectance")
            if np.iscomplexobj(rho) or np.any((rho < 0) | (rho > 1)):
                raise InvalidInputError(f"substrate reflectance must lie in [0, 1] (a Lambertian reflectance), got {self.reflectance!r}")

    @staticmethod
    def black() -> "Substrate":
        return Substrate(reflectance=0.0)

    @staticmethod
    def white(reflectance: float = 1.0) -> "Substrate":
        return Substrate(reflectance=reflectance)


@dataclass(frozen=True)
class CoatStack:
    """Coats top first on a substrate, under an ambient of real index ``n_ambient``."""

    coats: tuple
    substrate: Substrate = field(default_factory=Substrate.black)
    n_ambient: float = 1.0

    def __post_init__(self):
        object.__setattr__(self, "coats", tuple(self.coats))
        if not self.coats:
            raise InvalidInputError("a stack needs at least one coat")
        for c in self.coats:
            if not isinstance(c, Coat):
                raise InvalidInputError("coats must be nmmm.layers.coat_stack.Coat")
        if not isinstance(self.substrate, Substrate):
            raise InvalidInputError("substrate must be a nmmm.layers.coat_stack.Substrate")

    def replace(self, **kw) -> "CoatStack":
        d = dict(coats=self.coats, substrate=self.substrate, n_ambient=self.n_ambient)
        d.update(kw)
        return CoatStack(**d)


@dataclass(frozen=True)
class StackADResult:
    """Fluxes of a stack (fractions of the incident power) over the batch."""

    reflectance: np.ndarray  # collimated normal incidence, specular included
    specular_reflectance: np.ndarray
    transmittance: np.ndarray  # into a dielectric substrate (0 otherwise)
    diffuse_reflectance: np.ndarray  # Lambertian incidence
    reflectance_factor_45: np.ndarray  # 0°:45°a (= 45°a:0° by reciprocity), specular excluded


@dataclass(frozen=True)
class StackReflectance:
    wavelength_nm: np.ndarray
    reflectance: np.ndarray
    solver: str
    geometry: str
    optics: tuple  # MixtureOptics per coat


# --------------------------------------------------------------------------------------
# AD kernel


def _breaks(n_list):
    """Increasing squared indices per batch element, the order fixed by the mean values."""
    n = np.stack(n_list, axis=-1)  # (B, K)
    order = np.argsort(np.mean(n, axis=0), kind="stable")
    b = n[:, order] ** 2
    uniq = [0]
    for j in range(1, b.shape[1]):
        if np.all(np.abs(b[:, j] - b[:, uniq[-1]]) < 1e-12):
            continue
        uniq.append(j)
    b = b[:, uniq]
    for j in range(1, b.shape[1]):  # strictly increasing (crossing dispersions are clamped)
        b[:, j] = np.maximum(b[:, j], b[:, j - 1] * (1 + 1e-9) + 1e-12)
    return b


def _medium_limit(n, b):
    """Squared index used for the medium n (its break point), (B,)."""
    n2 = n**2
    j = np.argmin(np.abs(b - n2[:, None]), axis=1)
    return b[np.arange(b.shape[0]), j]


def _interface(u, na2, nb2):
    """Diagonal flux operators (R from a, T a→b, R from b, T b→a) of an interface, (B, N) each."""
    pa, pb = u < na2[:, None], u < nb2[:, None]
    ca = np.sqrt(np.clip(1 - u / na2[:, None], 1e-16, 1))
    ang = np.degrees(np.arccos(ca))
    with np.errstate(invalid="ignore"):
        r = fresnel(np.sqrt(na2)[:, None], np.sqrt(nb2)[:, None], ang).R
    r = np.where(pa & pb, r, 1.0)
    Ra = np.where(pa, r, 0.0)
    Rb = np.where(pb, np.where(pa, r, 1.0), 0.0)
    T = np.where(pa & pb, 1 - r, 0.0)
    return Ra, T, Rb, T


def _untrap(M):
    """A node totally reflected on both sides of a lossless layer (u between its index and
    both neighbours') is a trapped mode no outside light reaches: its row of I − R_a R_b is 0.
    Put 1 on its diagonal, so its (zero) source gives zero flux instead of a singular solve."""
    trapped = np.all(np.abs(M) < 1e-13, axis=-1)
    if np.any(trapped):
        M = M.copy()
        b, i = np.nonzero(trapped)
        M[b, i, i] = 1.0
    return M


def _combine(A, B):
    """Adding of A above B; each (R_top, T_down, R_bottom, T_up) of (B, N, N)."""
    Rat, Tad, Rab, Tau = A
    Rbt, Tbd, Rbb, Tbu = B
    I = np.eye(Rat.shape[-1])[None]
    X = np.linalg.solve(_untrap(I - Rab @ Rbt), Tad)
    Y = np.linalg.solve(_untrap(I - Rbt @ Rab), Tbu)
    return (Rat + Tau @ Rbt @ X, Tbd @ X, Rbb + Tbd @ Rab @ Y, Tau @ Y)


def _diag(*v):
    return tuple(x[:, :, None] * np.eye(x.shape[-1])[None] for x in v)


def stack_adding_doubling(albedo, optical_thickness, phase_moments, n_layers, n_ambient=1.0, substrate_reflectance=None,
                          substrate_nk=None, quad_pts: int | None = None) -> StackADResult:
    """Adding–doubling through a stack of scattering slabs, top first (module docstring).

    Parameters
    ----------
    albedo, optical_thickness, n_layers : sequences (one per slab) of arrays (B,)
        Real slab indices; optical thickness may be ``np.inf`` (opaque).
    phase_moments : sequence of arrays (B, L) (χ_0 = 1)
    n_ambient : float
    substrate_reflectance : array (B,), optional — a Lambertian substrate in optical contact.
    substrate_nk : array (B,) complex, optional — a Fresnel substrate (default: the ambient
        index below, i.e. a free film in air).
    quad_pts : int, optional — total nodes (even); default: chosen for 1e-4 accuracy.
    """
    K = len(n_layers)
    n_l = [np.atleast_1d(np.asarray(n, dtype=float)) for n in n_layers]
    Bn = max(x.size for x in n_l)
    n_l = [np.broadcast_to(x, (Bn,)) for x in n_l]
    a_l = [np.broadcast_to(np.asarray(x, dtype=float), (Bn,)) for x in albedo]
    t_l = [np.broadcast_to(np.asarray(x, dtype=float), (Bn,)) for x in optical_thickness]
    chi_l = [np.broadcast_to(np.atleast_2d(np.asarray(c, dtype=float)), (Bn, np.shape(c)[-1])) for c in phase_moments]
    if any(np.any((a < 0) | (a > 1)) for a in a_l):
        raise InvalidInputError("albedo must lie in [0, 1]")
    if any(np.any(np.isnan(t) | (t < 0)) for t in t_l):
        raise InvalidInputError("optical_thickness must be >= 0")
    n0 = np.full(Bn, float(n_ambient))
    if np.any(np.stack(n_l) < n0[0]):
        raise InvalidInputError("coat indices must be >= the ambient index (air above the stack)")
    real_below = substrate_reflectance is None and (substrate_nk is None or np.all(np.imag(substrate_nk) == 0))
    nsub = None
    if substrate_reflectance is None:
        nsub = np.broadcast_to(n0 if substrate_nk is None else np.asarray(substrate_nk), (Bn,))
    media = [n0] + n_l + ([np.real(nsub).astype(float)] if real_below else [])
    b = _breaks(media)
    if quad_pts is None:
        def chi_of(m):
            return (np.concatenate([c[:, 1] for c in chi_l]),
                    np.concatenate([c[:, m] if m < c.shape[1] else np.zeros(Bn) for c in chi_l]))
        N = auto_quad_pts(chi_of)
    else:
        N = int(quad_pts)
        if N < 4 or N % 2:
            raise InvalidInputError("quad_pts must be an even integer >= 4")
    nint = b.shape[1]
    first = N // 2
    rest = max(2, int(np.ceil((N - first) / max(nint - 1, 1))))
    counts = [first] + [rest] * (nint - 1)
    u, wu = snell_quadrature(b, counts)
    Nt = u.shape[1]
    n2 = [_medium_limit(x, b) for x in media]

    def slab_ops(j):
        prop = u[0] < n2[j + 1][0]  # the node count of a medium is the same over the batch
        idx = np.nonzero(prop)[0]
        m = idx.size
        uu, ww = u[:, idx], wu[:, idx]
        nn2 = n2[j + 1][:, None]
        nu = np.sqrt(np.clip(1 - uu / nn2, 1e-300, 1))
        w = ww / (2 * nn2 * nu)
        chi = chi_l[j]
        chi = chi[:, : m + 1] if chi.shape[1] >= m + 1 else np.concatenate([chi, np.zeros((Bn, m + 1 - chi.shape[1]))], axis=1)
        Rr, Tr = _slab(a_l[j].copy(), t_l[j].copy(), chi, nu, w, m)
        c = 2 * nu * w
        Rf = c[:, :, None] * Rr / c[:, None, :]
        Tf = c[:, :, None] * Tr / c[:, None, :]
        R = np.zeros((Bn, Nt, Nt))
        T = np.zeros((Bn, Nt, Nt))
        R[:, idx[:, None], idx[None, :]] = Rf
        T[:, idx[:, None], idx[None, :]] = Tf
        return (R, T, R, T)

    # bottom: substrate
    nl2 = n2[K]
    if substrate_reflectance is not None:
        rho = np.broadcast_to(np.asarray(substrate_reflectance, dtype=float), (Bn,))
        cl = np.where(u < nl2[:, None], wu / nl2[:, None], 0.0)
        Rsub = rho[:, None, None] * cl[:, :, None] * (u < nl2[:, None])[:, None, :]
        Tsub = np.zeros((Bn, Nt))
    else:
        cosl = np.sqrt(np.clip(1 - u / nl2[:, None], 1e-16, 1))
        ang = np.degrees(np.arccos(cosl))
        r = fresnel(np.sqrt(nl2)[:, None], nsub[:, None], ang).R
        prop = u < nl2[:, None]
        rs = np.where(prop, r, 0.0)
        Rsub = rs[:, :, None] * np.eye(Nt)[None]
        Tsub = np.where(prop, 1 - r, 0.0) if real_below else np.zeros((Bn, Nt))
    Z = np.zeros((Bn, Nt, Nt))
    below = (Rsub, Tsub[:, :, None] * np.eye(Nt)[None], Z, Z)
    for j in range(K - 1, -1, -1):
        below = _combine(slab_ops(j), below)
        Ra, T1, Rb, T2 = _interface(u, n2[j], n2[j + 1])
        below = _combine(_diag(Ra, T1, Rb, T2), below)
    Rtot, Ttot = below[0], below[1]
    spec = fresnel(n_ambient, np.sqrt(n2[1]), 0.0).R
    c0 = np.where(u < n2[0][:, None], wu / n2[0][:, None], 0.0)
    Rcol = Rtot[:, :, 0].sum(axis=1)
    Tcol = Ttot[:, :, 0].sum(axis=1)
    Rdif = np.einsum("bij,bj->b", Rtot, c0)
    # reflectance factor at 45° in the ambient: outgoing flux per node / Lambertian flux per node
    body = Rtot[:, :, 0].copy()
    body[:, 0] -= spec
    n_air = int(np.sum(u[0] < n2[0][0]))
    rf = body[:, :n_air] / np.maximum(c0[:, :n_air], 1e-300)
    u45 = 0.5 * n_ambient**2
    rf45 = np.array([np.interp(u45, u[i, :n_air], rf[i]) for i in range(Bn)])
    return StackADResult(Rcol, np.broadcast_to(spec, (Bn,)).copy(), Tcol, Rdif, rf45)


# --------------------------------------------------------------------------------------
# coats -> optics -> solvers


def coat_optics(coat: Coat, wavelength_nm, n_moments: int = AD_AUTO_QUAD_PTS[-1] + 1) -> MixtureOptics:
    """The coat's μ_a, μ_s, phase moments (a clear coat: its binder's absorption only)."""
    w = as_wavelength_nm(np.atleast_1d(wavelength_nm))
    if coat.components:
        return mixture_optics(coat.components, coat.binder, w, coat.dependent_scattering, coat.cpvc, n_moments)
    nb = np.broadcast_to(medium_nk(coat.binder, w, f"binder of coat {coat.name!r}"), w.shape)
    alpha = 4 * np.pi * nb.imag / w
    return MixtureOptics(w, alpha, np.zeros_like(w), np.tile(np.eye(1, n_moments), (w.size, 1)), nb.real, alpha, 0.0, 0.0)


def _substrate_args(sub: Substrate, w):
    if sub.reflectance is not None:
        return dict(substrate_reflectance=np.broadcast_to(np.asarray(sub.reflectance, dtype=float), w.shape))
    return dict(substrate_nk=np.broadcast_to(medium_nk(sub.compound, w, "substrate"), w.shape))


def _ad(stack: CoatStack, w, opts, geometry, quad_pts=None):
    from nmmm.layers.geometries import geometry_reflectance

    alb = [o.albedo for o in opts]
    tau = [(o.mu_a_per_nm + o.mu_s_per_nm) * c.thickness_nm if np.isfinite(c.thickness_nm)
           else np.full(w.shape, np.inf) for o, c in zip(opts, stack.coats)]
    r = stack_adding_doubling(alb, tau, [o.phase_moments for o in opts], [o.n_binder for o in opts], stack.n_ambient,
                              quad_pts=quad_pts, **_substrate_args(stack.substrate, w))
    return geometry_reflectance(geometry, "ad", ad=r)


def _km(stack: CoatStack, w, opts, geometry, quad_pts=None):
    from nmmm.layers.geometries import geometry_reflectance
    from nmmm.layers.kubelka_munk import km_coefficients, km_reflectance, km_transmittance

    sub = stack.substrate
    if sub.reflectance is None:
        nl = opts[-1].n_binder
        r = fresnel(nl, medium_nk(sub.compound, w, "substrate"), 0.0).R  # diffuse ~ normal (a KM simplification)
        Rg = np.broadcast_to(r, w.shape)
    else:
        Rg = np.broadcast_to(np.asarray(sub.reflectance, dtype=float), w.shape)
    R = Rg
    for o, c in zip(opts[::-1], stack.coats[::-1]):
        K, S = km_coefficients(o.mu_a_per_nm, o.mu_s_per_nm, o.g)
        X = c.thickness_nm if np.isfinite(c.thickness_nm) else 1e15
        if np.all(S == 0):
            # non-scattering coat: diffuse transmittance 2E3(K X/2) both ways (K = 2 mu_a)
            from scipy.special import expn

            t = 2 * expn(3, K * X / 2)
            R = t * t * R
            continue
        R1 = km_reflectance(K, S, X, 0.0)
        T1 = km_transmittance(K, S, X)
        R = R1 + T1**2 * R / (1 - R1 * R)  # Kubelka (1954)
    return geometry_reflectance(geometry, "km", body=np.asarray(R, float), n_top=opts[0].n_binder)


#: stack solvers: name -> function(stack, wavelengths, optics per coat, geometry, quad_pts)
STACK_SOLVERS = {"ad": _ad, "km": _km}


def stack_reflectance(stack: CoatStack, wavelength_nm: ArrayLike, solver: str = "ad", geometry: str = "di:8",
                      quad_pts: int | None = None, optics: Sequence[MixtureOptics] | None = None) -> StackReflectance:
    """Reflectance of a coat stack as the instrument ``geometry`` reports it.

    ``geometry``: a name of :data:`nmmm.layers.geometries.GEOMETRIES` ("di:8", "de:8",
    "45a:0", "0:45a", "0:d"). ``optics``: the coats' :class:`MixtureOptics` if already
    computed (sweeps over thickness or substrate reuse them).
    """
    from nmmm.layers.geometries import check_geometry

    check_geometry(geometry)
    if solver not in STACK_SOLVERS:
        raise InvalidInputError(f"unknown solver {solver!r}; choose from {sorted(STACK_SOLVERS)}")
    w = as_wavelength_nm(np.atleast_1d(wavelength_nm))
    opts = tuple(coat_optics(c, w) for c in stack.coats) if optics is None else tuple(optics)
    R = STACK_SOLVERS[solver](stack, w, opts, geometry, quad_pts)
    return StackReflectance(w, np.asarray(R, float), solver, geometry, opts)
