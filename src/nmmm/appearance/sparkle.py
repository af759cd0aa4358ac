"""Sparkle and graininess of effect paints, measured on an image.

The same function applies to a rendered spectral/RGB image of a plate and to a
photograph of a real plate: the image is reduced to relative luminance (linear data, or
sRGB-encoded 8/16-bit photographs decoded first), normalised by its median (so that the
exposure does not matter), and analysed at physical scales given by the pixel size.

Metric (documented here; the industrial BYK-mac sparkle grades S_a, S_i and graininess G
use proprietary formulas and cannot be reproduced exactly):

1. **Background**: B = Gaussian low-pass of the luminance Y at ``background_um``
   (default 500 µm, several flake spacings).
2. **Sparkles** under directional light: connected regions where
   Y > (1 + ``threshold_contrast``)·B (default: twice the local background), each
   counted once; its *contrast* is (max Y − B)/B at its peak. Reported: number per mm²
   (``density_per_mm2``), area fraction, mean and 90th-percentile peak contrast, and the
   **sparkle intensity** S = area fraction × mean log2(1 + contrast) — how much of the
   surface glints, and how strongly (a logarithmic response, as in brightness perception).
3. **Graininess** (the salt-and-pepper texture seen under diffuse light, also computed on
   any image): the coefficient of variation of Y band-passed between the visual acuity
   at reading distance (``acuity_um`` = 50 µm, the smallest visible detail quoted by the
   seed paper) and ``background_um``: G = std(G_acuity ∗ Y − G_background ∗ Y) / mean(Y).

Public functions
----------------
- :func:`relative_luminance` — Y from an RGB or luminance image (linear or sRGB).
- :func:`sparkle_graininess` -> :class:`SparkleMetrics`.
- :func:`flake_glint_image` — a quick luminance image of the glints of a
  :class:`~nmmm.appearance.flakes.FlakeList` for one lighting/viewing pair (each flake
  a disc whose brightness is its reflection seen through an angular acceptance cone), to
  connect flake lists and the metric without a full renderer.

The same metric predicted from the flake statistics (number density, size, tilt, depth),
without an image: :mod:`nmmm.appearance.sparkle_prediction`.

References
----------
- C. S. McCamy, "Observation and measurement of the appearance of metallic materials.
  Part II. Micro appearance", Color Res. Appl. 23 (1998) 362.
- E. Kirchner, G.-J. van den Kieboom, L. Njo, R. Supèr, R. Gottenbos, "Observation of
  visual texture of metallic and pearlescent materials", Color Res. Appl. 32 (2007) 256.
- IEC 61966-2-1:1999 — sRGB decoding; ITU-R BT.709 luminance coefficients.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["relative_luminance", "sparkle_graininess", "SparkleMetrics", "flake_glint_image"]

_BT709 = np.array([0.2126, 0.7152, 0.0722])


def relative_luminance(image, encoding: str = "linear") -> np.ndarray:
    """Relative luminance Y (H, W) of a luminance (H, W) or RGB(A) (H, W, 3|4) image.

    ``encoding="linear"`` for rendered / raw linear data; ``"srgb"`` for display-encoded
    photographs (integers are scaled by their dtype's maximum first, then the sRGB
    transfer function is inverted, IEC 61966-2-1).
    """
    a = np.asarray(image)
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] not in (1, 3, 4)):
        raise InvalidInputError(f"image must be (H, W), (H, W, 3) or (H, W, 4), got shape {a.shape}")
    if a.shape[0] == 0 or a.shape[1] == 0:
        raise InvalidInputError(f"image has no pixels (shape {a.shape}); give an image at least 1 x 1")
    if a.dtype.kind in "ui":
        a = a.astype(float) / np.iinfo(a.dtype).max
    a = check_finite(a, "image").astype(float)
    if encoding not in ("linear", "srgb"):
        raise InvalidInputError(f"encoding must be 'linear' or 'srgb', got {encoding!r}")
    if encoding == "srgb":
        a = np.where(a <= 0.04045, a / 12.92, ((np.clip(a, 0, None) + 0.055) / 1.055) ** 2.4)
    if a.ndim == 3:
        a = a[..., 0] if a.shape[2] == 1 else a[..., :3] @ _BT709
    if np.any(a < 0):
        raise InvalidInputError("image has negative values; give luminance or RGB >= 0")
    return a


@dataclass(frozen=True)
class SparkleMetrics:
    """Result of :func:`sparkle_graininess` (see the module docstring)."""

    n_sparkles: int
    density_per_mm2: float
    area_fraction: float
    mean_contrast: float
    p90_contrast: float
    sparkle_intensity: float
    graininess: float
    pixel_size_um: float
    image_area_mm2: float

    def as_dict(self) -> dict:
        return asdict(self)


def sparkle_graininess(image, pixel_size_um: float, encoding: str = "linear", threshold_contrast: float = 1.0,
                       background_um: float = 500.0, acuity_um: float = 50.0, min_area_px: int = 1) -> SparkleMetrics:
    """Sparkle and graininess of an image of a paint (render or photograph).

    Parameters
    ----------
    image : array (H, W) or (H, W, 3)
        Luminance or RGB; ``encoding`` says whether it is linear or sRGB-encoded.
    pixel_size_um : float
        Size of one pixel on the plate (µm); sets the physical scales.
    threshold_contrast : float
        A pixel belongs to a sparkle when Y > (1 + threshold_contrast) × local background.
    background_um, acuity_um : float
        Scales (µm) of the background low-pass and of the visual acuity.
    min_area_px : int
        Smallest sparkle kept (pixels).
    """
    from scipy import ndimage

    ps = float(check_finite(pixel_size_um, "pixel_size_um"))
    if not ps > 0:
        raise InvalidInputError(f"pixel_size_um must be > 0, got {pixel_size_um!r}")
    if not float(threshold_contrast) > 0:
        raise InvalidInputError("threshold_contrast must be > 0")
    if not (0 < acuity_um < background_um):
        raise InvalidInputError("need 0 < acuity_um < background_um")
    Y = relative_luminance(image, encoding)
    h, w = Y.shape
    area_mm2 = h * w * (ps * 1e-3) ** 2
    med = float(np.median(Y))
    mean = float(Y.mean())
    if mean <= 0:
        raise InvalidInputError("the image is black; nothing to measure")
    Yn = Y / (med if med > 0 else mean)
    sig_bg = background_um / ps / 2.0  # Gaussian σ ≈ half the named scale (FWHM ~ scale)
    sig_ac = acuity_um / ps / 2.0
    B = ndimage.gaussian_filter(Yn, sig_bg, mode="reflect")
    # background without the sparkles themselves: a robust second pass
    mask0 = Yn > (1 + threshold_contrast) * B
    if mask0.any():
        Yc = np.where(mask0, B, Yn)
        B = ndimage.gaussian_filter(Yc, sig_bg, mode="reflect")
    B = np.maximum(B, 1e-12)
    mask = Yn > (1 + threshold_contrast) * B
    lab, n = ndimage.label(mask)
    if n:
        idx = np.arange(1, n + 1)
        areas = ndimage.sum(np.ones_like(Yn), lab, idx)
        contrast_map = Yn / B - 1.0
        peaks = ndimage.maximum(contrast_map, lab, idx)
        keep = areas >= min_area_px
        areas, peaks = areas[keep], peaks[keep]
        n = int(keep.sum())
    else:
        areas = peaks = np.zeros(0)
    area_fraction = float(areas.sum() / (h * w))
    mean_c = float(peaks.mean()) if n else 0.0
    p90 = float(np.percentile(peaks, 90)) if n else 0.0
    intensity = area_fraction * (float(np.mean(np.log2(1 + peaks))) if n else 0.0)
    band = ndimage.gaussian_filter(Yn, sig_ac, mode="reflect") - ndimage.gaussian_filter(Yn, sig_bg, mode="reflect")
    graininess = float(band.std() / Yn.mean())
    return SparkleMetrics(n, n / area_mm2, area_fraction, mean_c, p90, intensity, graininess, ps, area_mm2)


def flake_glint_image(paint, flakes, wavelength_nm, wi, wo, pixel_size_um: float = 10.0,
                      acceptance_deg: float = 1.0, background: bool = True) -> np.ndarray:
    """Luminance-like image (H, W) of a flake list's glints for one (wi, wo) pair.

    Each flake reflects light into its mirror direction (:func:`flake_list_reflection`);
    it is seen from ``wo`` with a Gaussian angular acceptance of ``acceptance_deg`` (the
    solid angle subtended by the pupil and the light source), drawn as a disc of its
    diameter. The smooth part of the BRDF (base, multiple scattering, coat) is added as a
    uniform background when ``background``. Radiance is integrated against the CIE ȳ
    curve (D65-free, equal-energy light): a quick preview for the sparkle metric and for
    tests, not a renderer.
    """
    from nmmm.appearance.brdf import flake_list_reflection
    from nmmm.colour import weighting_factors

    w = np.asarray(wavelength_nm, float)
    wo = np.asarray(wo, float).reshape(3)
    Wy = weighting_factors(w, illuminant=np.ones_like(w), observer="10")[:, 1] / 100.0  # Y of a white = 1
    dirs, power, esc = flake_list_reflection(paint, flakes, w, wi)
    ps = float(pixel_size_um) * 1e3  # nm
    nx = max(int(np.ceil(flakes.region_nm[0] / ps)), 1)
    ny = max(int(np.ceil(flakes.region_nm[1] / ps)), 1)
    sig = np.radians(acceptance_deg)
    ang = np.arccos(np.clip(dirs @ wo, -1, 1))
    # radiance factor: flake power spread over the acceptance solid angle (2π σ²), per area
    weight = np.exp(-0.5 * (ang / sig) ** 2) / (2 * np.pi * sig * sig) * esc
    Yk = (power @ Wy) * weight * np.pi / max(wo[2], 1e-6)  # reflectance-factor units on the patch
    img = np.zeros((ny, nx))
    area_patch = flakes.region_nm[0] * flakes.region_nm[1]
    for k in np.flatnonzero((ang < 4 * sig) & (Yk > 0)):
        r = flakes.diameters_nm[k] / 2
        cx, cy = flakes.positions_nm[k]
        x0, x1 = int(max((cx - r) // ps, 0)), int(min((cx + r) // ps + 1, nx))
        y0, y1 = int(max((cy - r) // ps, 0)), int(min((cy + r) // ps + 1, ny))
        if x1 <= x0 or y1 <= y0:
            continue
        xs = (np.arange(x0, x1) + 0.5) * ps
        ys = (np.arange(y0, y1) + 0.5) * ps
        disc = ((xs[None, :] - cx) ** 2 + (ys[:, None] - cy) ** 2) <= r * r
        if not disc.any():  # a flake smaller than a pixel: all its light in the pixel of its centre
            disc[min(max(int(cy // ps) - y0, 0), y1 - y0 - 1), min(max(int(cx // ps) - x0, 0), x1 - x0 - 1)] = True
        npx = disc.sum()
        # the flake's share of the patch's reflectance factor, concentrated on its pixels
        img[y0:y1, x0:x1] += disc * Yk[k] * (area_patch / (ps * ps)) / npx
    if background:
        smooth = paint(w, np.asarray(wi, float), wo, components=("base", "multiple", "specular"))
        img += float(np.pi * smooth @ Wy)
    return img
