"""Cross-check of nmmm's plate renderer against Mitsuba 3 (an independent renderer), region by region.

The same scene — a flat painted plate in z = 0, point lights and/or a uniform spectral sky, a
pinhole camera — is rendered twice:

- by :func:`nmmm.appearance.render.render_plate` (deterministic: BRDF × irradiance per light,
  directional albedo × sky radiance, no sampling), and
- by Mitsuba 3's ``path`` integrator with the ``nmmm_paint`` BSDF
  (:mod:`nmmm.appearance.render.mitsuba_paint`, the same BRDF tabulated) through
  :func:`nmmm.appearance.render.mitsuba_scene.render_object` (Monte Carlo, ``spp`` samples
  per pixel, low-discrepancy sampler by default).

The plate pixels (eroded by one pixel, so that Mitsuba's pixels half on the plate, which its
box filter averages with the background, are left out) are cut into a ``grid`` of regions and
the mean radiance (averaged over the wavelength grid) of each region is compared. The Monte-Carlo
standard error of each Mitsuba region mean is estimated from the scatter of the per-pixel
difference Mitsuba − nmmm inside the region (pixels are independent estimates; the smooth
image's own gradient inside the region drops out of the difference).

Flakes are compared as the statistical BRDF (``PaintedPlate(brdf)`` without a flake list: no
glints): the discrete glints are a different estimator of the same mean (tested elsewhere).

Public objects
--------------
- :class:`PlateCrossCheck` — both images, region means, relative deviations and standard errors.
- :func:`crosscheck_plate` — render both and compare.
- :func:`plate_regions` — the (rows, cols) pixel slices and masks of a grid over the plate.

References
----------
- W. Jakob et al., "Mitsuba 3 renderer" (2022), https://mitsuba-renderer.org — ``path``
  integrator, ``ldsampler`` (Kollig & Keller 2002 (0, 2)-sequences).
- M. Pharr, W. Jakob, G. Humphreys, *Physically Based Rendering*, 4th ed. (2023) §2.1
  (Monte-Carlo estimators, standard error).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError

__all__ = ["PlateCrossCheck", "crosscheck_plate", "plate_regions"]


def plate_regions(on_plate, grid=(3, 3), erode: int = 1):
    """``[(slice_rows, slice_cols, mask), ...]`` (row-major, ``grid`` = (rows, cols)) of the
    plate pixels ``on_plate`` (H, W) eroded by ``erode`` pixels, cut into equal parts of
    their bounding box."""
    from scipy.ndimage import binary_erosion

    on = np.asarray(on_plate, bool)
    if erode > 0:
        on = binary_erosion(on, iterations=int(erode))
    gy, gx = (int(g) for g in grid)
    if gy < 1 or gx < 1:
        raise InvalidInputError(f"grid must be (rows, cols) >= 1, got {grid!r}")
    rows, cols = np.nonzero(on)
    if rows.size < gy * gx:
        raise InvalidInputError(f"the plate covers {rows.size} interior pixels, fewer than the {gy} x {gx} regions: "
                                "raise the resolution or narrow fov_deg")
    re = np.linspace(rows.min(), rows.max() + 1, gy + 1).astype(int)
    ce = np.linspace(cols.min(), cols.max() + 1, gx + 1).astype(int)
    out = []
    for i in range(gy):
        for j in range(gx):
            sr, sc = slice(re[i], re[i + 1]), slice(ce[j], ce[j + 1])
            out.append((sr, sc, on[sr, sc]))
    return out


@dataclass(frozen=True, repr=False)
class PlateCrossCheck:
    """Result of :func:`crosscheck_plate`: ``mitsuba`` and ``nmmm``
    (:class:`~nmmm.appearance.render.plate.SpectralImage`), region means ``mean_mitsuba``,
    ``mean_nmmm`` (grid-shaped, radiance averaged over λ), ``deviation`` (Mitsuba / nmmm − 1),
    ``standard_error`` (relative Monte-Carlo standard error of each Mitsuba region mean),
    ``pixels`` per region, ``band_deviation`` (L,) of the whole plate's mean per wavelength."""

    mitsuba: object
    nmmm: object
    mean_mitsuba: np.ndarray
    mean_nmmm: np.ndarray
    deviation: np.ndarray
    standard_error: np.ndarray
    pixels: np.ndarray
    band_deviation: np.ndarray
    info: dict = field(default_factory=dict)

    def __repr__(self):
        return (f"<PlateCrossCheck {self.deviation.shape[0]}x{self.deviation.shape[1]} regions: "
                f"max |dev| {100 * np.abs(self.deviation).max():.2f} %, max s.e. {100 * self.standard_error.max():.2f} %>")

    def table(self) -> str:
        """The regions as text: Mitsuba / nmmm mean radiance, deviation and standard error."""
        lines = ["region  mitsuba      nmmm         dev %   s.e. %  pixels"]
        gy, gx = self.deviation.shape
        for i in range(gy):
            for j in range(gx):
                lines.append(f"({i},{j})   {self.mean_mitsuba[i, j]:<11.5g}  {self.mean_nmmm[i, j]:<11.5g}  "
                             f"{100 * self.deviation[i, j]:+6.2f}  {100 * self.standard_error[i, j]:6.2f}  "
                             f"{int(self.pixels[i, j])}")
        return "\n".join(lines)


def crosscheck_plate(brdf, lights=(), environment=None, position_mm=(0.0, -250.0, 300.0), look_at_mm=(0.0, 0.0, 0.0),
                     fov_deg: float = 35.0, resolution=(48, 32), spp: int = 1024, wavelength_nm=None,
                     plate_size_mm=(150.0, 100.0), grid=(3, 3), sampler: str = "ldsampler", coarse_step: int = 1,
                     seed: int = 0, table=None, variant: str = "llvm_ad_spectral") -> PlateCrossCheck:
    """Render the plate painted with ``brdf`` by nmmm and by Mitsuba 3 and compare region means.

    ``lights``: nmmm :class:`~nmmm.appearance.render.PointLight` / ``DirectionalLight`` (point
    lights of zero radius: a lamp of finite size is drawn by nmmm only in the coat's mirror);
    ``environment``: a :class:`~nmmm.appearance.render.UniformEnvironment`, a
    :class:`~nmmm.appearance.render.LatLongEnvironment` (e.g. :meth:`ViewingBooth.environment`:
    Mitsuba gets it as the ``nmmm_envmap`` emitter) or None.
    ``coarse_step`` is nmmm's smooth-grid step (1: every pixel; the default 4 of
    :func:`render_plate` interpolates a peaky flake lobe bilinearly, ≈1.4 % off at its top).
    ``table``: :func:`~nmmm.appearance.render.mitsuba_paint.paint_table` options.
    Raises :class:`~nmmm.appearance.render.mitsuba_paint.MitsubaUnavailableError` without Mitsuba.
    """
    from nmmm.appearance.render.camera import PinholeCamera
    from nmmm.appearance.render.lights import default_wavelengths
    from nmmm.appearance.render.mitsuba_scene import render_object
    from nmmm.appearance.render.plate import PaintedPlate, render_plate

    w = default_wavelengths() if wavelength_nm is None else np.asarray(wavelength_nm, float).ravel()
    pos = tuple(float(v) for v in position_mm)
    f = np.asarray(look_at_mm, float) - np.asarray(pos)
    up = (0.0, 0.0, 1.0) if np.linalg.norm(np.cross(f / np.linalg.norm(f), [0.0, 0.0, 1.0])) > 1e-3 else (0.0, 1.0, 0.0)
    from nmmm.appearance.render.lights import LatLongEnvironment

    menv = environment._on(w) if isinstance(environment, LatLongEnvironment) else environment
    (mimg,) = render_object(brdf, "plate", list(lights), menv, position_mm=pos, look_at_mm=look_at_mm,
                            fov_deg=fov_deg, resolution=resolution, spp=spp, wavelength_nm=w,
                            plate_size_mm=plate_size_mm, sampler=sampler, table=table, seed=seed, variant=variant)
    cam = PinholeCamera(pos, tuple(float(v) for v in look_at_mm), up, fov_deg, tuple(int(v) for v in resolution))
    pimg = render_plate(PaintedPlate(brdf, size_mm=plate_size_mm), cam, list(lights), environment,
                        wavelength_nm=w, coarse_step=coarse_step)
    M = mimg.radiance.mean(axis=2).astype(float)
    P = pimg.radiance.mean(axis=2).astype(float)
    regs = plate_regions(pimg.on_plate, grid)
    gy, gx = (int(g) for g in grid)
    mm, mp, se, npx = (np.zeros(gy * gx) for _ in range(4))
    for k, (sr, sc, mk) in enumerate(regs):
        a, b = M[sr, sc][mk], P[sr, sc][mk]
        mm[k], mp[k], npx[k] = a.mean(), b.mean(), a.size
        se[k] = np.std(a - b, ddof=1) / np.sqrt(a.size) / b.mean()
    inner = np.zeros_like(pimg.on_plate)
    for sr, sc, mk in regs:
        inner[sr, sc] |= mk
    band = mimg.radiance[inner].mean(axis=0) / pimg.radiance[inner].mean(axis=0) - 1
    shape = (gy, gx)
    return PlateCrossCheck(mimg, pimg, mm.reshape(shape), mp.reshape(shape), (mm / mp - 1).reshape(shape),
                           se.reshape(shape), npx.reshape(shape), band,
                           {"spp": int(spp), "sampler": sampler, "coarse_step": int(coarse_step),
                            "resolution": tuple(int(v) for v in resolution), "wavelengths": int(w.size)})
