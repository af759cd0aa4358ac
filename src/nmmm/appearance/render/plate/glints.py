"""The glints of the discrete flakes of a plate: the cell's tilt variants
(``_tilt_variants``) and the driver ``_render_glints`` (visible tiles, grid on the flake
normals, the search of :mod:`~nmmm.appearance.render.plate.glint_search`, the splat of
:mod:`~nmmm.appearance.render.plate.splatting`).
"""

from __future__ import annotations

import math

import numpy as np

from nmmm.appearance.render.lights import DirectionalLight
from nmmm.appearance.render.plate.glint_search import _glint_tiles
from nmmm.appearance.render.plate.splatting import _glint_splat


#: tilt variants of the unit cell (see :func:`_tilt_variants`): enough copies for
#: ~2·10⁵ distinct flake tilts, at most 64, and at most 8·10⁶ entries of normal grids
_TILT_SAMPLE_TARGET = 200_000
_MAX_TILT_VARIANTS = 64
_MAX_GRID_ENTRIES = 8_000_000
#: glint records held at once (~64 bytes each, plus the sort's copies)
_MAX_RECORDS = 4_000_000


#: the cut of a rough-faced flake's facet lobe, in units of its width (GGX: a flake's facets
#: beyond 8 α hold 1/65 = 1.5 % of its light, dropped from the image and from the prediction)
ROUGH_LOBE_CUT = 8.0


def rough_cut_rad(alpha: float, sigma: float, n: float) -> float:
    """The facet-offset cut (rad) of a rough-faced glint: ``ROUGH_LOBE_CUT`` α_eff at normal
    light and view (α_eff² = α² + 2 σ_g² / (4 n²)), at most 35°."""
    return min(ROUGH_LOBE_CUT * math.sqrt(alpha * alpha + 2 * sigma * sigma / (4 * n * n)), math.radians(35.0))


def _tilt_variants(fl, n_var: int) -> np.ndarray:
    """``n_var`` copies (n_var, N, 3) of the cell's flake normals with the tilts θ_k moved
    by a Cranley–Patterson rotation of their cumulative probability,
    θ_k^(v) = F⁻¹((F(θ_k) + v / n_var) mod 1), azimuths kept (variant 0 = the cell).

    Why: tiling repeats the cell's N flakes, and the per-tile rotation about the plate
    normal changes only their azimuths, so without variants every tile has the *same* N
    tilt magnitudes. The glint density around a light's highlight (half vector h' at
    angle θh from the normal) is then the cell's empirical tilt histogram, which at small
    θ holds a handful of flakes (grey metallic seed cell, N = 2103, σ = 12°: 1.9 expected
    below 0.5°, 7.4 below 1°) — a deterministic dark (or bright) spot or ring at the
    mirror point that no amount of averaging over pixels removes. Each variant's tilts
    still follow F exactly (the shift maps a uniform variable to a uniform one), and the
    union over variants is stratified in F, so the tile-averaged density of normals is
    the model p(θ) down to θ = 0. F is the cell's tilt distribution (``fl.tilt``), or a
    kernel estimate of its normals when unknown (deposit cells)."""
    from nmmm.appearance.flakes import TiltDistribution

    nrm = np.asarray(fl.normals, float)
    if n_var <= 1:
        return np.ascontiguousarray(nrm[None])
    tilt = getattr(fl, "tilt", None)
    if tilt is None:
        tilt = TiltDistribution.from_normals(nrm)
    th = np.degrees(np.arccos(np.clip(nrm[:, 2], -1.0, 1.0)))
    ph = np.arctan2(nrm[:, 1], nrm[:, 0])
    cdf = np.asarray(tilt._cdf, float)
    u = np.interp(th, tilt.tilt_deg, cdf)
    # each flake its own shift per variant, ((v + c_k) mod n_var + r_k) / n_var: stratified over
    # the variants for every flake, independent between the flakes of one variant. A shift
    # common to all flakes of a variant moved the flakes of one rank band together, so where
    # the cell's tilts correlate with depth or area (deposits: weights e^{−τ_e S ζ − κ S' z})
    # a tile's bright flakes glinted in step and the pixel variance exceeded the compound
    # Poisson law of independent flakes (red metallic, rough faces: 1.3–1.6× at 450 nm)
    rng = np.random.default_rng(0x5EED)
    ck = rng.integers(0, n_var, size=nrm.shape[0])
    rk = rng.random(nrm.shape[0])
    shifts = (((np.arange(n_var)[:, None] + ck[None, :]) % n_var) + rk[None, :]) / n_var
    th_v = np.radians(np.interp((u[None, :] + shifts) % 1.0, cdf, tilt.tilt_deg))
    th_v[0] = np.radians(th)  # variant 0: the cell itself
    s = np.sin(th_v)
    out = np.stack([s * np.cos(ph), s * np.sin(ph), np.cos(th_v)], axis=-1)
    return np.ascontiguousarray(out)


def _render_glints(plate, camera, lights, spectra, w, sigma, P_on, img, randomize_tiles=True, tile_seed=0,
                   area_splat=True):
    fl = plate.flakes
    tab = plate.smooth_brdf.prepare(w)
    n = float(tab.n)
    cw, ch = plate.cell_mm
    nx, ny = plate.cells
    hx, hy = plate.size_mm[0] / 2, plate.size_mm[1] / 2
    # visible tiles
    xmin, ymin = P_on[:, 0].min(), P_on[:, 1].min()
    xmax, ymax = P_on[:, 0].max(), P_on[:, 1].max()
    i0 = max(int(math.floor((xmin + hx) / cw)) - 1, 0)
    i1 = min(int(math.floor((xmax + hx) / cw)) + 2, nx)
    j0 = max(int(math.floor((ymin + hy) / ch)) - 1, 0)
    j1 = min(int(math.floor((ymax + hy) / ch)) + 2, ny)
    # flakes of the unit cell (mm) and a grid on their normals
    fpos = np.ascontiguousarray(fl.positions_nm * 1e-6)
    fnrm = np.ascontiguousarray(fl.normals)
    farea = fl.areas_nm2 * 1e-12
    fdiam = np.ascontiguousarray(np.asarray(fl.diameters_nm, float) * 1e-6)
    # attenuation by the flakes above each flake: exp(-τ_e S ζ) with ζ = τ_above / τ, the
    # same mean-field factor as nmmm.appearance.brdf.flake_list_reflection (flakes that
    # transmit: ζ times the flake layer's optical depth per direction, _Tables.optical_path)
    if hasattr(fl, "optical_depth_above") and fl.optical_depth > 0:
        fzeta = np.asarray(fl.optical_depth_above(), float) / fl.optical_depth
    else:
        top, bottom = fl.layer_depth_nm
        fzeta = np.clip((fl.depth_nm - top) / max(bottom - top, 1e-9), 0.0, 1.0)
    # the pigments of a pigmented basecoat (κ = (μa + μs) H, flakes in the band z0 … z0 + dz):
    # flake k lies at z0 + dz ζ_k — its rank in depth mapped onto the band, so that the
    # flakes' mean e^{−τ_e S ζ − κ S' (z0 + dz ζ)} is the statistical term's
    # e^{−κ z0 S'} (1 − e^{−X})/X, X = τ_e S + κ dz S' (nmmm.appearance.brdf.effect_tables)
    kappa = np.ascontiguousarray(np.broadcast_to(np.asarray(getattr(tab, "kappa", 0.0), float), (w.size,)))
    fpig = np.ascontiguousarray(float(getattr(tab, "z0", 0.0)) + float(getattr(tab, "dz", 1.0)) * fzeta)
    cut = 3.0
    mfac = min(2.0, 1.1 / (2 * math.sqrt(max(n * n - 1, 1e-6))))
    # rough flake faces (the paint's FlakeLayer.surface_roughness, GGX α): each glint's lobe is
    # the facet distribution of the statistical BRDF (TiltDistribution.roughened's law) widened
    # by the source's lobe, cut at rough_cut_rad (see glint_search._glint_tiles); the rims'
    # diffuse share f_e is already out of tab.Rf (it joins the smooth multiple-scattering lobe)
    pf = getattr(plate.smooth_brdf, "flakes", None)
    alpha = float(getattr(pf, "surface_roughness", 0.0) or 0.0)
    rcut = rough_cut_rad(alpha, sigma, n) if alpha > 0 else 0.0
    G = int(np.clip(4.0 / max(mfac * cut * sigma, rcut), 4, 512))
    if randomize_tiles:
        n_var = max(1, min(_MAX_TILT_VARIANTS, int(math.ceil(_TILT_SAMPLE_TARGET / max(len(fl), 1))),
                           int(_MAX_GRID_ENTRIES // (G * G + 1))))
        fnrm = _tilt_variants(fl, n_var)
    else:
        fnrm = fnrm[None]
    bx = np.clip(((fnrm[..., 0] + 1) * 0.5 * G).astype(np.int64), 0, G - 1)
    by = np.clip(((fnrm[..., 1] + 1) * 0.5 * G).astype(np.int64), 0, G - 1)
    key = by * G + bx
    order = np.ascontiguousarray(np.argsort(key, axis=1, kind="stable").astype(np.int64))
    gstart = np.ascontiguousarray(np.stack([np.searchsorted(kv[o], np.arange(G * G + 1))
                                            for kv, o in zip(key, order)]).astype(np.int64))
    nl = len(lights)
    lkind = np.array([0 if isinstance(lt, DirectionalLight) else 1 for lt in lights], np.int64)
    lvec = np.array([lt.direction if isinstance(lt, DirectionalLight) else lt.position_mm for lt in lights], float)
    lscale = np.ones(nl)  # the light spectra (espec) carry the irradiance / intensity
    cam = np.asarray(camera.position_mm, float)
    r, u, f = camera.basis()
    tx, ty = camera.tan_half
    sx, sy = camera.shift
    Wd, Hd = camera.resolution
    a_tab = np.ascontiguousarray(tab.a_tab, float)
    nrow = max(j1 - j0, 0)
    counts = np.zeros(nrow, np.int64)
    offsets = np.zeros(nrow, np.int64)
    e0 = np.zeros(0, np.int64)
    rest = (fpos, fnrm, farea, fdiam, fzeta, fpig, G, gstart, order, lkind, lvec, lscale, n, sigma, cut, a_tab,
            tab.step, bool(randomize_tiles), int(tile_seed), bool(area_splat), alpha, rcut)
    head = (cam, r, u, f, tx, ty, sx, sy, Wd, Hd, hx, hy, cw, ch, i0, i1)
    _glint_tiles(False, offsets, e0, np.zeros(0), np.zeros((0, 5)), e0, counts, *head, j0, j1, *rest)
    total = int(counts.sum())
    if total == 0:
        return 0
    espec = np.ascontiguousarray(np.stack(spectra), float)
    tau_e = np.ascontiguousarray(np.broadcast_to(tab.tau_e, (w.size,)), float)
    flat = img.reshape(-1, w.size)
    const_tau = bool(np.ptp(tau_e) <= 1e-12 * max(1.0, float(tau_e.max())) and not np.any(kappa > 0))
    # flakes that transmit: the flake layer's extinction per direction, as the BRDF (issue 18) —
    # the records also carry the internal angles and ζ/μ' (9 columns), the splat reads tab.ext_tab
    transmit = bool(tab.has_flakes and not tab.tau_e_const)
    ncol = 9 if transmit else 5
    ext = np.ascontiguousarray(tab.ext_tab, float)
    if transmit:
        const_tau = False
    max_records = _MAX_RECORDS * 5 // ncol
    # rows of tiles in chunks of at most _MAX_RECORDS glint records (rough faces give every
    # flake of the plate a record: 4e7 for a 15 x 10 cm red metallic, 6 GB at once)
    csum = np.cumsum(counts)
    ja = 0
    while ja < nrow:
        base = csum[ja - 1] if ja > 0 else 0
        jb = max(int(np.searchsorted(csum, base + max_records, side="right")), ja + 1)
        cnt = counts[ja:jb].copy()
        m = int(cnt.sum())
        if m:
            offs = np.zeros(jb - ja, np.int64)
            offs[1:] = np.cumsum(cnt)[:-1]
            rec_pix = np.empty(m, np.int64)
            rec_w = np.empty(m)
            rec_th = np.empty((m, ncol))
            rec_li = np.empty(m, np.int64)
            _glint_tiles(True, offs, rec_pix, rec_w, rec_th, rec_li, cnt, *head, j0 + ja, j0 + jb, *rest)
            srt = np.argsort(rec_pix, kind="stable")
            rec_pix, rec_w, rec_th, rec_li = rec_pix[srt], rec_w[srt], rec_th[srt], rec_li[srt]
            starts = np.flatnonzero(np.r_[True, rec_pix[1:] != rec_pix[:-1], True]).astype(np.int64)
            _glint_splat(flat, starts, rec_pix, rec_w, rec_th, rec_li, np.ascontiguousarray(tab.Tc),
                         np.ascontiguousarray(tab.Rf), tab.step, tau_e, const_tau, espec, kappa, ext)
            del rec_pix, rec_w, rec_th, rec_li, srt
        ja = jb
    return total
