"""The paint BRDF object: :class:`PaintBRDF` (coat, base reflectance, optional flake layer)
and the names of its terms :data:`COMPONENTS`. The model is described in
:mod:`nmmm.appearance.brdf`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nmmm.appearance.brdf.clear_coat import ClearCoat
from nmmm.appearance.brdf.coat_medium import CoatMedium
from nmmm.appearance.brdf.fused_kernel import _nb
from nmmm.appearance.brdf.interpolation import _deg, _lerp_table
from nmmm.appearance.brdf.ms_azimuth import add_azimuth_modes
from nmmm.appearance.brdf.tables import _Tables
from nmmm.appearance.flakes import FlakeLayer, check_directions
from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = ["COMPONENTS", "PaintBRDF"]

#: the names of the BRDF terms, for ``evaluate(..., components=...)``
COMPONENTS = ("specular", "flakes", "base", "multiple")

_CHUNK = 16384


@dataclass(frozen=True, repr=False)
class PaintBRDF:
    """Spectral BRDF of a clear-coated paint (see the module docstring for the model).

    Parameters
    ----------
    coat : ClearCoat
        Index and roughness of the clear coat (shared with the binder).
    body_reflectance : scalar, callable, (wavelength_nm, values) or array on the grid
        Internal diffuse reflectance ρ(λ) ∈ [0, 1] of the pigmented base under the
        binder (no air-interface correction). 0: black or absent base.
    flakes : FlakeLayer or None
        Flake optics, tilt distribution and optical depth; None for a solid paint.
    name : str
    medium : CoatMedium or None
        The pigmented binder of the basecoat around the flakes (absorption, scattering, g,
        thickness): radiative transfer in the coat (:mod:`~nmmm.appearance.brdf.effect_tables`).
        ``body_reflectance`` is then the substrate (primer) under the basecoat. None: the
        pigments act only through ``body_reflectance`` (a Lambertian base under the flakes).
    """

    coat: ClearCoat = field(default_factory=ClearCoat)
    body_reflectance: object = 0.0
    flakes: FlakeLayer | None = None
    name: str = "paint"
    medium: CoatMedium | None = None
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.coat, ClearCoat):
            raise InvalidInputError("coat must be a ClearCoat")
        if self.flakes is not None and not isinstance(self.flakes, FlakeLayer):
            raise InvalidInputError("flakes must be a FlakeLayer or None")
        if self.medium is not None and not isinstance(self.medium, CoatMedium):
            raise InvalidInputError("medium must be a CoatMedium (nmmm.appearance.brdf.CoatMedium) or None")

    def __repr__(self):
        fl = "no flakes" if self.flakes is None else f"flakes tau={self.flakes.optical_depth:.3g} ({self.flakes.tilt.name})"
        med = "" if self.medium is None else f", in {self.medium!r}"
        return f"<PaintBRDF '{self.name}': coat alpha={self.coat.roughness:g}, {fl}{med}>"

    # -- tables ------------------------------------------------------------------------
    def prepare(self, wavelength_nm) -> "_Tables":
        """Build (and cache) the tables for a wavelength grid (done automatically)."""
        w = as_wavelength_nm(wavelength_nm).ravel()
        key = w.tobytes()
        tab = self._cache.get(key)
        if tab is None:
            if len(self._cache) > 8:
                self._cache.clear()
            fl = self.flakes
            effect = fl is not None and (fl.depth_range != (0.0, 1.0) or fl.surface_roughness > 0
                                         or fl.edge_fraction > 0)
            if self.medium is not None or effect:
                from nmmm.appearance.brdf.effect_tables import _EffectTables

                tab = _EffectTables(self, w)
            else:
                tab = _Tables(self, w)
            self._cache[key] = tab
        return tab

    # -- evaluation --------------------------------------------------------------------
    def evaluate(self, wavelength_nm, wi, wo, components=COMPONENTS, dtype=np.float64,
                 method: str = "numba", below_surface: str = "raise") -> np.ndarray:
        """f(λ, ωi, ωo) in 1/sr.

        ``wi``, ``wo``: unit vectors ``(..., 3)`` (broadcast together), z >= 0; a
        direction below the surface raises :class:`InvalidInputError`. Returns
        ``broadcast_shape + (n_wavelengths,)``. ``components`` selects terms among
        ``COMPONENTS = ("specular", "flakes", "base", "multiple")``. The Dirac of a smooth
        coat is not included (see :meth:`specular_reflectance`). ``method``: "numba" (a
        fused parallel kernel, default) or "numpy" (chunked array code, same equations).
        ``dtype=np.float32`` halves the memory of large evaluations.
        ``below_surface="zero"`` returns 0 for pairs with a direction below the surface
        instead of raising (for renderers whose samples may leave the hemisphere).
        """
        if method not in ("numba", "numpy"):
            raise InvalidInputError(f"method must be 'numba' or 'numpy', got {method!r}")
        if below_surface not in ("raise", "zero"):
            raise InvalidInputError(f"below_surface must be 'raise' or 'zero', got {below_surface!r}")
        tab = self.prepare(wavelength_nm)
        comps = _check_components(components)
        below = None
        if below_surface == "zero":
            wi = np.array(check_finite(wi, "wi"), dtype=float)
            wo = np.array(check_finite(wo, "wo"), dtype=float)
            shape = np.broadcast_shapes(wi.shape, wo.shape)
            wi, wo = np.broadcast_to(wi, shape).copy(), np.broadcast_to(wo, shape).copy()
            below = (wi[..., 2] < 0) | (wo[..., 2] < 0)
            wi[below] = (0.0, 0.0, 1.0)
            wo[below] = (0.0, 0.0, 1.0)
            below = below.reshape(-1)
        wi = _checked_directions(wi, "wi")
        wo = _checked_directions(wo, "wo")
        shape = np.broadcast_shapes(wi.shape, wo.shape)[:-1]
        wi = np.broadcast_to(wi, shape + (3,)).reshape(-1, 3)
        wo = np.broadcast_to(wo, shape + (3,)).reshape(-1, 3)
        out = np.empty((wi.shape[0], tab.L), dtype=dtype)
        if method == "numba" and _nb is not None:
            tab.evaluate_fast(wi, wo, comps, out)
        else:
            for s in range(0, wi.shape[0], _CHUNK):
                out[s:s + _CHUNK] = tab.evaluate(wi[s:s + _CHUNK], wo[s:s + _CHUNK], comps)
        if "multiple" in comps and not getattr(tab, "fuses_ms_azimuth", False):
            add_azimuth_modes(tab, wi, wo, out)  # a separate pass unless the tables' kernels include it
        if below is not None and below.any():
            out[below] = 0.0
        return out.reshape(shape + (tab.L,))

    __call__ = evaluate

    def specular_reflectance(self, wavelength_nm, wi) -> np.ndarray:
        """Weight of the mirror Dirac of a smooth coat (its Fresnel reflectance) for
        incidence ``wi`` (..., 3) -> (..., L); zeros for a rough coat (whose specular
        lobe is part of :meth:`evaluate`)."""
        tab = self.prepare(wavelength_nm)
        wi = check_directions(wi, "wi")
        shape = wi.shape[:-1]
        th = _deg(wi.reshape(-1, 3)[:, 2])
        if self.coat.roughness > 0:
            return np.zeros(shape + (tab.L,))
        return _lerp_table(tab.Fs, th, tab.step).reshape(shape + (tab.L,))

    def albedo(self, wavelength_nm, wi) -> np.ndarray:
        """Directional–hemispherical reflectance (all terms, Dirac included) for
        incidence ``wi`` (..., 3) -> (..., L), from the model's albedo tables."""
        tab = self.prepare(wavelength_nm)
        wi = check_directions(wi, "wi")
        shape = wi.shape[:-1]
        th = _deg(wi.reshape(-1, 3)[:, 2])
        a = _lerp_table(tab.albedo_nodes()[0], th, tab.step)
        return a.reshape(shape + (tab.L,))

    def lossless_albedo(self, wavelength_nm, wi) -> np.ndarray:
        """Directional albedo of the same paint made lossless (flake absorption → reflection,
        ρ = 1): 1 by construction; exposed for checks."""
        tab = self.prepare(wavelength_nm)
        wi = check_directions(wi, "wi")
        th = _deg(wi.reshape(-1, 3)[:, 2])
        a = _lerp_table(tab.albedo_nodes()[1], th, tab.step)
        return a.reshape(wi.shape[:-1] + (tab.L,))

    def bin_average(self, wavelength_nm, wi, theta_edges_deg, phi_edges_deg, components=COMPONENTS,
                    n_quad: int = 8) -> np.ndarray:
        """Cosine-weighted mean of the BRDF over angular bins of outgoing directions
        (θ edges × φ edges, degrees): ∫_bin f cos θ dω / ∫_bin cos θ dω ->
        (nθ, nφ, L). Gauss–Legendre with ``n_quad``² nodes per bin."""
        te = np.radians(np.asarray(theta_edges_deg, float))
        pe = np.radians(np.asarray(phi_edges_deg, float))
        x, wx = np.polynomial.legendre.leggauss(n_quad)
        tl, th_ = te[:-1, None], te[1:, None]
        tq = 0.5 * (th_ - tl) * (x + 1) + tl  # (nt, q)
        wt = 0.5 * (th_ - tl) * wx
        pl, ph = pe[:-1, None], pe[1:, None]
        pq = 0.5 * (ph - pl) * (x + 1) + pl
        wp = 0.5 * (ph - pl) * wx
        T = tq[:, None, :, None]
        P = pq[None, :, None, :]
        dirs = np.stack(np.broadcast_arrays(np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)), axis=-1)
        f = self.evaluate(wavelength_nm, np.asarray(wi, float), dirs, components)
        wgt = (wt * np.sin(tq) * np.cos(tq))[:, None, :, None] * wp[None, :, None, :]
        num = np.einsum("abij,abijl->abl", wgt, f)
        den = wgt.sum(axis=(2, 3))
        return num / den[..., None]

    # -- derived -----------------------------------------------------------------------
    def with_(self, **changes) -> "PaintBRDF":
        """A copy with some fields changed (the table cache is not shared)."""
        from dataclasses import replace

        return replace(self, _cache={}, **changes)


def _unit_rows_py(a, out):
    """out = a / |a| row by row (a (P, 3)); False unless every row is finite, of unit length within
    1e-6 and has z >= 0 — the conditions and the numbers of ``check_directions`` in one pass."""
    ok = True
    for p in range(a.shape[0]):
        x, y, z = a[p, 0], a[p, 1], a[p, 2]
        nrm = np.sqrt(x * x + y * y + z * z)
        if not abs(nrm - 1.0) <= 1e-6:  # also NaN and infinite entries
            ok = False
        out[p, 0] = x / nrm
        out[p, 1] = y / nrm
        out[p, 2] = z / nrm
        if out[p, 2] < 0.0:
            ok = False
    return ok


_unit_rows = _nb.njit(cache=True)(_unit_rows_py) if _nb is not None else None  # no fastmath: the same roundings


def _checked_directions(v, name):
    """``check_directions(v, name)`` (its result to the bit; 2 passes instead of 8 over 10^6 pairs);
    any doubt — other dtype or layout, a row that fails — goes to check_directions, which raises."""
    a = np.asarray(v)
    if _unit_rows is None or a.dtype != np.float64 or a.ndim < 1 or a.shape[-1] != 3 or not a.flags.c_contiguous:
        return check_directions(v, name)
    out = np.empty(a.shape)
    if not _unit_rows(a.reshape(-1, 3), out.reshape(-1, 3)):
        return check_directions(v, name)
    return out


def _check_components(components):
    if isinstance(components, str):
        components = (components,)
    comps = tuple(components)
    bad = [c for c in comps if c not in COMPONENTS]
    if bad:
        raise InvalidInputError(f"unknown BRDF component(s) {bad}; choose among {COMPONENTS}")
    return frozenset(comps)
