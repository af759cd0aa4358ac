"""Wavelength-by-wavelength (point-by-point) inversion of n and k, and its Kramers–Kronig check.

Public objects
--------------
- :func:`point_by_point` — n, k of one layer (or of the substrate) at every measured
  wavelength, all other parameters of the model held fixed.
- :class:`PointByPointResult` — the constants with their uncertainties, χ² per wavelength,
  ``material()`` (a TabulatedMaterial), ``write_csv()`` (a Material file).
- :func:`kk_check` — Kramers–Kronig consistency of the inverted constants
  (:func:`nmmm.materials.kk_consistency`).
- :func:`batched_levenberg_marquardt` — the engine: independent small least-squares
  problems solved side by side, vectorised across them.

Method
------
At each wavelength λ_j the unknowns x_j = (n_j, k_j) minimise
χ²_j = Σ_angles [(Ψ_mod − Ψ)/σΨ]² + [wrap(Δ_mod − Δ)/σΔ]². The problems are independent,
so one Levenberg–Marquardt iteration advances all of them at once: a single call of
``Stack.rt`` on every data point evaluates the model, finite differences in n and k (two more
calls) give each wavelength's 2×2 normal matrix, and the damped steps are solved as a batch
(Marquardt 1963; Press et al. 2007, ch. 15). The start is the model's current material for
that layer — typically a dispersion fit — which selects the physical branch among the
multiple solutions of the ellipsometric equations for transparent films (Fujiwara 2007,
ch. 5). Uncertainties are √diag (JᵀJ)⁻¹ per wavelength (scaled by χ²_j/dof_j when the data
carry no σ and several angles give dof_j > 0).

Point-by-point constants carry no causality constraint: :func:`kk_check` tests whether the
inverted n and k are consistent with each other (Kramers–Kronig); a large deviation flags
a wrong thickness or an inadequate model (Fujiwara 2007, ch. 5).

References
----------
- H. Fujiwara, *Spectroscopic Ellipsometry*, Wiley (2007), ch. 5 (KK relations, direct inversion).
- D. W. Marquardt, J. Soc. Ind. Appl. Math. 11, 431 (1963), doi:10.1137/0111030.
- W. H. Press et al., *Numerical Recipes*, 3rd ed. (2007), ch. 15.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from nmmm.ellipsometry.forward import psi_delta_from_rho, wrap_delta
from nmmm.errors import ConvergenceError, InvalidInputError

__all__ = ["point_by_point", "PointByPointResult", "kk_check", "batched_levenberg_marquardt", "group_wavelengths"]


def group_wavelengths(wavelength_nm, rtol: float = 1e-9):
    """(unique wavelengths, index of each point's wavelength) — points measured at one wavelength
    at several angles form a group."""
    w = np.asarray(wavelength_nm, dtype=float)
    order = np.argsort(w, kind="stable")
    ws = w[order]
    new = np.empty(ws.size, dtype=bool)
    new[0] = True
    new[1:] = np.diff(ws) > rtol * ws[1:]
    gid_sorted = np.cumsum(new) - 1
    gid = np.empty_like(gid_sorted)
    gid[order] = gid_sorted
    unique = ws[new]
    return unique, gid


def batched_levenberg_marquardt(residuals, x0, group, lower=None, upper=None, *, max_iter: int = 100,
                                tol: float = 1e-12, step=None):
    """Solve G independent least-squares problems of p unknowns each, vectorised.

    Parameters
    ----------
    residuals : callable
        ``residuals(x) -> r`` with ``x`` of shape (G, p) and ``r`` of shape (N, m): the m
        residuals of each of the N data points; point i belongs to problem ``group[i]``.
    x0 : ndarray (G, p)
    group : int ndarray (N,)
    lower, upper : ndarray (p,) or (G, p), optional
        Bounds (steps are clipped into them).
    max_iter, tol : stopping rule: relative decrease of χ² below ``tol`` with a step accepted.
    step : ndarray (p,), optional
        Finite-difference steps (default 1e-6·max(|x|, 1)).

    Returns
    -------
    x : ndarray (G, p)
    info : dict
        ``chi2`` (G,), ``jtj`` (G, p, p), ``n_points`` (G,), ``converged`` (G,) bool,
        ``iterations``, ``history`` (list of total χ²).
    """
    x = np.array(x0, dtype=float, copy=True)
    G, p = x.shape
    group = np.asarray(group)
    lo = np.full((G, p), -np.inf) if lower is None else np.broadcast_to(lower, (G, p)).astype(float)
    hi = np.full((G, p), np.inf) if upper is None else np.broadcast_to(upper, (G, p)).astype(float)
    x = np.clip(x, lo, hi)
    n_pts = np.bincount(group, minlength=G)

    def cost_of(r):
        return np.bincount(group, weights=np.sum(r * r, axis=1), minlength=G)

    def normal(x, r):
        J = np.empty(r.shape + (p,))
        for q in range(p):
            h = (1e-6 * np.maximum(np.abs(x[:, q]), 1.0)) if step is None else np.full(G, step[q])
            # step inward when at the upper bound
            h = np.where(x[:, q] + h > hi[:, q], -h, h)
            xq = x.copy()
            xq[:, q] += h
            J[..., q] = (residuals(xq) - r) / h[group, None]
        JtJ = np.zeros((G, p, p))
        Jtr = np.zeros((G, p))
        np.add.at(JtJ, group, np.einsum("nmi,nmj->nij", J, J))
        np.add.at(Jtr, group, np.einsum("nmi,nm->ni", J, r))
        return JtJ, Jtr

    r = residuals(x)
    cost = cost_of(r)
    lam = np.full(G, 1e-3)
    converged = np.zeros(G, dtype=bool)
    history = [float(cost.sum())]
    it = 0
    for it in range(1, max_iter + 1):
        JtJ, Jtr = normal(x, r)
        diag = np.einsum("gii->gi", JtJ)
        A = JtJ + lam[:, None, None] * (np.eye(p) * np.maximum(diag, 1e-30)[:, None, :])
        # active bounds (projected step): a variable on a bound whose descent direction points
        # outward is held there, so that the others still converge (e.g. k = 0 where transparent)
        active = ((x <= lo) & (Jtr > 0)) | ((x >= hi) & (Jtr < 0))
        if active.any():
            keep = ~active
            A = A * (keep[:, :, None] & keep[:, None, :]) + np.eye(p) * active[:, None, :]
            Jtr = np.where(active, 0.0, Jtr)
        try:
            dx = -np.linalg.solve(A, Jtr[..., None])[..., 0]
        except np.linalg.LinAlgError:
            dx = -np.linalg.lstsq(A.reshape(-1, p), Jtr.reshape(-1), rcond=None)[0].reshape(G, p)
        dx = np.where(converged[:, None], 0.0, dx)
        x_try = np.clip(x + dx, lo, hi)
        r_try = residuals(x_try)
        cost_try = cost_of(r_try)
        better = (cost_try <= cost) & ~converged
        rel = np.where(cost > 0, (cost - cost_try) / np.maximum(cost, 1e-300), 0.0)
        small_step = np.all(np.abs(x_try - x) <= 1e-12 * np.maximum(np.abs(x), 1.0), axis=1)
        newly = better & ((rel < tol) | small_step) | (cost < 1e-24)
        x = np.where(better[:, None], x_try, x)
        take = better[group]
        r = np.where(take[:, None], r_try, r)
        cost = np.where(better, cost_try, cost)
        lam = np.where(better, lam / 5.0, lam * 10.0)
        # no downhill step even with a tiny, gradient-like step: a minimum to working precision
        converged |= newly | (lam > 1e10)
        history.append(float(cost.sum()))
        if converged.all():
            break
    JtJ, _ = normal(x, r)
    return x, {"chi2": cost, "jtj": JtJ, "n_points": n_pts, "converged": converged, "iterations": it,
               "history": history, "lambda": lam}


@dataclass(frozen=True, repr=False)
class PointByPointResult:
    """n, k inverted at each wavelength.

    Attributes
    ----------
    wavelength_nm : ndarray (G,)
    nk : complex ndarray (G,)
    sigma_n, sigma_k : ndarray (G,)
        Standard uncertainties (NaN where the data cannot give them: one angle, no σ).
    chi2 : ndarray (G,)
    converged : bool ndarray (G,)
    layer : str
    """

    wavelength_nm: np.ndarray
    nk: np.ndarray
    sigma_n: np.ndarray
    sigma_k: np.ndarray
    chi2: np.ndarray
    converged: np.ndarray
    layer: str
    info: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        return (f"<PointByPointResult '{self.layer}': {self.wavelength_nm.size} wavelengths "
                f"{self.wavelength_nm.min():g}-{self.wavelength_nm.max():g} nm>")

    @property
    def eps(self) -> np.ndarray:
        return self.nk**2

    def material(self, name: str | None = None):
        """The constants as a :class:`~nmmm.materials.material.TabulatedMaterial`."""
        from nmmm.materials.material import TabulatedMaterial

        return TabulatedMaterial(name or f"{self.layer} (point-by-point)", self.wavelength_nm, self.nk.real,
                                 np.maximum(self.nk.imag, 0.0),
                                 reference="nmmm.ellipsometry.point_by_point_inversion inversion")

    def write_csv(self, path, name: str | None = None) -> Path:
        """Write a Material CSV (``wavelength_nm,n,k,sigma_n,sigma_k``) for ``nmmm.materials.read_csv``."""
        from nmmm.ellipsometry.data import write_material_csv

        return write_material_csv(path, self.wavelength_nm, self.nk.real + 1j * np.maximum(self.nk.imag, 0),
                                  name=name or f"{self.layer} (point-by-point)",
                                  reference="nmmm.ellipsometry.point_by_point_inversion inversion",
                                  sigma_n=self.sigma_n, sigma_k=self.sigma_k)


def _uncertainties(info, has_sigma: bool, n_res_per_point: int):
    jtj = info["jtj"]
    G, p, _ = jtj.shape
    cov = np.full((G, p, p), np.nan)
    ok = np.abs(np.linalg.det(jtj)) > 1e-300
    cov[ok] = np.linalg.inv(jtj[ok])
    dof = info["n_points"] * n_res_per_point - p
    if not has_sigma:
        scale = np.where(dof > 0, info["chi2"] / np.maximum(dof, 1), np.nan)
        cov = cov * scale[:, None, None]
    return np.sqrt(np.abs(np.einsum("gii->gi", cov)))


def _raise_unconverged(what: str, wl, info, advice: str):
    """ConvergenceError listing the wavelengths (of ``wl``) where ``info["converged"]`` is False."""
    conv = info["converged"]
    if conv.all():
        return
    bad = wl[~conv]
    raise ConvergenceError(
        f"{what} did not converge at {bad.size} wavelength(s) "
        f"({', '.join(f'{b:g}' for b in bad[:8])}{' ...' if bad.size > 8 else ''} nm) {advice}",
        history=info["history"])


def point_by_point(data, model, layer: str, values: dict | None = None, start=None, *, max_iter: int = 100,
                   raise_on_failure: bool = True) -> PointByPointResult:
    """Invert n and k of ``layer`` at every measured wavelength, the rest of the model fixed.

    Parameters
    ----------
    data : EllipsometryData
        One or several angles; at each wavelength all angles are used together.
    model : EllipsometryModel
        The sample; its parameter values (``values``, default the model's own — e.g.
        ``fit_result.values``) fix thicknesses and the other layers.
    layer : str
        Name of the layer to invert, or ``"substrate"`` (a bulk sample). A roughness layer
        directly on it follows the inverted n + ik (Bruggeman mixture with void at each step).
    start : complex array_like, optional
        Start n + ik per unique wavelength (default: the layer's model material).
    raise_on_failure : bool
        Raise :class:`ConvergenceError` listing the wavelengths that did not converge
        (default); with False they are flagged in ``result.converged``.

    Returns
    -------
    PointByPointResult
    """
    from nmmm.ellipsometry.model import make_stack

    v = model.values if values is None else dict(values)
    wl, gid = group_wavelengths(data.wavelength_nm)
    G = wl.size
    media = model.media(v)
    names = [n for n, _, _ in media]
    if layer != "substrate" and layer not in names:
        raise InvalidInputError(f"no layer {layer!r} to invert; layers: {names} or 'substrate'")
    if start is None:
        target = model.material(layer, v)
        start = target.nk(wl, extrapolate=False)
    start = np.broadcast_to(np.asarray(start, dtype=complex), (G,))
    x0 = np.stack([start.real, np.maximum(start.imag, 0.0)], axis=-1)
    ambient = model.ambient.build(v)
    substrate = model.substrate.build(v)
    w_pts = data.wavelength_nm
    a_pts = data.angle_deg
    sp = data.sigma_psi_deg if data.has_sigma else 1.0
    sd = data.sigma_delta_deg if data.has_sigma else 1.0
    # materials of the other layers evaluated once on the data points
    fixed = [(name, m.nk(w_pts), t) for name, m, t in media]
    # a roughness layer directly on the inverted medium mixes *its* n + ik with void (Bruggeman)
    below = [lay.name for lay in model.layers[1:]] + ["substrate"]
    rough_on_target = {lay.name: lay.fraction_void for lay, under in zip(model.layers, below)
                       if lay.roughness and under == layer}
    eps_void = ambient.eps(w_pts)

    def nk_of(name, nkv, nk):
        if name == layer:
            return nk
        if name in rough_on_target:
            from nmmm.ema.bruggeman_rule import bruggeman
            from nmmm.materials.material import eps_to_nk

            return eps_to_nk(bruggeman(eps_void, nk * nk, rough_on_target[name]))
        return nkv

    def residuals(x):
        nk = (x[:, 0] + 1j * x[:, 1])[gid]
        lay = [(nk_of(name, nkv, nk), t) for name, nkv, t in fixed]
        sub = nk if layer == "substrate" else substrate
        stack = make_stack(ambient, lay, sub)
        res = stack.rt(w_pts, a_pts, grid=False)
        psi, delta = psi_delta_from_rho(res.rp / res.rs)
        return np.stack([(psi - data.psi_deg) / sp, wrap_delta(delta - data.delta_deg) / sd], axis=-1)

    x, info = batched_levenberg_marquardt(residuals, x0, gid, lower=np.array([1e-6, 0.0]),
                                          upper=np.array([np.inf, np.inf]), max_iter=max_iter)
    sig = _uncertainties(info, data.has_sigma, 2)
    conv = info["converged"]
    if raise_on_failure:
        _raise_unconverged(f"point-by-point inversion of {layer!r}", wl, info,
                           f"in {max_iter} iterations; start from a better dispersion fit (start=) or raise "
                           "max_iter, or pass raise_on_failure=False to inspect result.converged")
    return PointByPointResult(wl, x[:, 0] + 1j * x[:, 1], sig[:, 0], sig[:, 1], info["chi2"], conv, layer, info)


def kk_check(result, tolerance: float = 0.02, **kwargs):
    """Kramers–Kronig consistency report of inverted constants (a PointByPointResult, or any
    Material), by :func:`nmmm.materials.kk_consistency` on the measured wavelengths.

    Returns the :class:`nmmm.materials.KKReport`; ``report.consistent(tolerance)`` says whether
    n and k agree with causality within ``tolerance`` in n (over the central part of the range).
    """
    from nmmm.materials import kk_consistency

    if isinstance(result, PointByPointResult):
        mat = result.material()
        w = result.wavelength_nm
    else:
        mat = result
        w = kwargs.pop("wavelength_nm", None)
    return kk_consistency(mat, wavelength_nm=w, **kwargs)
