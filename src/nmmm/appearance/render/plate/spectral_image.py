"""The rendered image: :class:`SpectralImage` — spectral radiance (H, W, L) and its colour
(XYZ, sRGB with exposure, Display P3), PNG and spectral OpenEXR output.

References
----------
- A. Fichet, R. Pacanowski, A. Wilkie, "An OpenEXR layout for spectral images", JCGT
  10(3) (2021) — the EXR channel layout.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from nmmm.appearance.render.camera import PinholeCamera
from nmmm.errors import InvalidInputError
from nmmm.spectra import check_finite

__all__ = ["SpectralImage", "TONE_MAP_KNEE"]

#: relative luminance (display white = 1) above which :meth:`SpectralImage.to_display` compresses
TONE_MAP_KNEE = 0.8
#: a channel counts as above display white beyond 1 + this (a tenth of the 8-bit step at white)
WHITE_TOLERANCE = 1e-3


@dataclass(frozen=True, repr=False)
class SpectralImage:
    """A rendered spectral radiance image.

    ``radiance`` (H, W, L) float32 in the lights' units × sr⁻¹; ``on_plate`` (H, W) mask;
    ``white_radiance`` (L,) radiance of a perfect white diffuser at the plate centre under
    the same lights (sets the default exposure and the adopted white).
    """

    wavelength_nm: np.ndarray
    radiance: np.ndarray
    on_plate: np.ndarray
    white_radiance: np.ndarray
    camera: PinholeCamera | None = None
    metadata: dict = field(default_factory=dict)

    def __repr__(self):
        h, w, L = self.radiance.shape
        return f"<SpectralImage {w}x{h}, {L} wavelengths {self.wavelength_nm[0]:g}-{self.wavelength_nm[-1]:g} nm>"

    def _weights(self):
        from nmmm.colour import weighting_factors

        # equal-energy weights: a flat spectrum of value 1 has Y = 100
        return weighting_factors(self.wavelength_nm, illuminant=np.ones(self.wavelength_nm.size))

    def to_xyz(self) -> np.ndarray:
        """CIE 1931 XYZ (H, W, 3) of the radiance, scaled so a flat radiance of 1 has Y = 100."""
        W = self._weights()
        return (self.radiance.reshape(-1, self.radiance.shape[-1]) @ W.astype(np.float32)).reshape(
            self.radiance.shape[:2] + (3,)).astype(float)

    @property
    def white_xyz(self) -> np.ndarray:
        return self.white_radiance @ self._weights()

    def exposure_scale(self, exposure: float = 1.0) -> float:
        """Multiplier putting the white diffuser at Y = 100, times ``exposure``."""
        yw = float(self.white_xyz[1])
        if not yw > 0:
            return float(exposure)
        return 100.0 / yw * float(exposure)

    def to_srgb(self, exposure: float = 1.0, clip: bool = True) -> np.ndarray:
        """Encoded sRGB (H, W, 3) in [0, 1]: ``exposure`` = 1 maps a perfect white diffuser
        under the same lights to display white (1, 1, 1); the lights' white is adapted to
        D65 (CAT02) via :func:`nmmm.colour.xyz_to_srgb`."""
        from nmmm.colour import xyz_to_srgb

        e = float(check_finite(exposure, "exposure"))
        if e <= 0:
            raise InvalidInputError(f"exposure must be > 0, got {exposure!r}")
        white = self.white_xyz
        return xyz_to_srgb(self.to_xyz(), white_xyz=white if white[1] > 0 else None, clip=clip,
                           exposure=self.exposure_scale(e))

    def to_display_rgb(self, colourspace: str = "sRGB", exposure: float = 1.0, clip: bool = True) -> np.ndarray:
        """Encoded RGB (H, W, 3) for a calibrated display: ``"sRGB"`` (IEC 61966-2-1) or
        ``"Display P3"`` (P3 primaries, D65, sRGB transfer curve), via colour-science; the
        lights' white is adapted to D65 (CAT02) and ``exposure`` = 1 maps a white diffuser
        to display white."""
        if colourspace == "sRGB":
            return self.to_srgb(exposure, clip)
        if colourspace not in ("Display P3",):
            raise InvalidInputError(f"colourspace must be 'sRGB' or 'Display P3', got {colourspace!r}")
        rgb, _ = self._display_rgb(colourspace, exposure, encode=True)
        return np.clip(rgb, 0.0, 1.0) if clip else rgb

    def _display_rgb(self, colourspace: str, exposure: float, encode: bool) -> tuple[np.ndarray, np.ndarray]:
        """RGB (H, W, 3) of ``colourspace`` at ``exposure`` (checked > 0), the lights' white adapted
        to D65 (CAT02), transfer curve applied when ``encode``; and the exposed XYZ (display white
        Y = 1) it came from. Shared by the display methods."""
        import colour

        e = float(check_finite(exposure, "exposure"))
        if e <= 0:
            raise InvalidInputError(f"exposure must be > 0, got {exposure!r}")
        white = self.white_xyz
        xyz = self.to_xyz() / 100.0 * self.exposure_scale(e)
        xy_w = colour.XYZ_to_xy(white / white[1]) if white[1] > 0 else colour.CCS_ILLUMINANTS[
            "CIE 1931 2 Degree Standard Observer"]["D65"]
        rgb = colour.XYZ_to_RGB(xyz, colour.RGB_COLOURSPACES[colourspace], illuminant=xy_w,
                                chromatic_adaptation_transform="CAT02", apply_cctf_encoding=encode)
        return np.asarray(rgb, float), xyz

    def to_display(self, colourspace: str = "sRGB", exposure: float = 1.0, tone_map: str = "knee",
                   knee: float = TONE_MAP_KNEE, display_white_cd_m2: float = 120.0):
        """Encoded RGB (H, W, 3) in [0, 1] for a calibrated display, and its statistics.

        **Exposure rule**: ``exposure`` = 1 maps a perfect white tile at the plate centre under
        the same lights (``white_radiance``; in a :class:`ViewingBooth` the booth's white tile)
        to display white, shown at ``display_white_cd_m2`` (120 cd/m² by default); the lights'
        white is adapted to D65 (CAT02).

        **Tone mapping** (``tone_map="knee"``): relative luminance x (display white = 1) is
        kept below ``knee`` and above it compressed as
        y = k + (1 − k)(1 − exp(−(x − k)/(1 − k))) — continuous with slope 1 at k, tending
        to display white — with the pixel's chromaticity kept (linear RGB scaled by y/x); a
        pixel with a channel still above 1 (a saturated colour near white) is desaturated
        towards the grey of the same luminance (rgb' = y + s (rgb − y), the largest s ≤ 1
        that fits), so its luminance y is shown and nothing is clipped.
        ``"none"``: linear RGB clipped at 1 (as :meth:`to_display_rgb`).

        Returns ``(rgb, stats)``, stats = ``{"clipped_fraction"`` (pixels with a channel
        clipped, i.e. above 1 + :data:`WHITE_TOLERANCE`), ``"over_white_fraction"`` (pixels with a channel above display white before
        the operator), ``"desaturated_fraction"``, ``"max_relative_luminance"``,
        ``"display_white_cd_m2"``, ``"plate_mean_cd_m2"`` (mean displayed luminance on the plate)}."""
        import colour

        if colourspace not in ("sRGB", "Display P3"):
            raise InvalidInputError(f"colourspace must be 'sRGB' or 'Display P3', got {colourspace!r}")
        if tone_map not in ("knee", "none"):
            raise InvalidInputError(f"tone_map must be 'knee' or 'none', got {tone_map!r}")
        k = float(check_finite(knee, "knee"))
        if not 0 < k < 1:
            raise InvalidInputError(f"knee must lie in (0, 1) (a fraction of display white), got {knee!r}")
        rgb, xyz = self._display_rgb(colourspace, exposure, encode=False)
        dw = float(check_finite(display_white_cd_m2, "display_white_cd_m2"))
        if dw <= 0:
            raise InvalidInputError(f"display_white_cd_m2 must be > 0, got {display_white_cd_m2!r}")
        space = colour.RGB_COLOURSPACES[colourspace]
        rgb = np.clip(rgb, 0.0, None)
        over = np.any(rgb > 1.0 + WHITE_TOLERANCE, axis=-1)
        x = np.clip(xyz[..., 1], 0.0, None)
        desat = np.zeros(x.shape, bool)
        if tone_map == "knee":
            y = np.where(x > k, k + (1 - k) * (1 - np.exp(-(x - k) / (1 - k))), x)
            rgb = rgb * np.where(x > 0, y / np.where(x > 0, x, 1.0), 1.0)[..., None]
            m = rgb.max(axis=-1)
            desat = m > 1.0 + WHITE_TOLERANCE
            sc = np.where(desat, (1.0 - y) / np.where(desat, m - y, 1.0), 1.0)[..., None]
            rgb = np.where(desat[..., None], y[..., None] + sc * (rgb - y[..., None]), rgb)
        else:
            y = np.minimum(x, 1.0)
        clipped = np.any(rgb > 1.0 + WHITE_TOLERANCE, axis=-1)
        rgb = np.clip(rgb, 0.0, 1.0)
        on = np.asarray(self.on_plate, bool)
        stats = {"clipped_fraction": float(clipped.mean()), "over_white_fraction": float(over.mean()),
                 "desaturated_fraction": float(desat.mean()),
                 "max_relative_luminance": float(x.max()) if x.size else 0.0, "display_white_cd_m2": dw,
                 "plate_mean_cd_m2": float(dw * np.minimum(y, 1.0)[on].mean()) if on.any() else 0.0}
        return np.asarray(space.cctf_encoding(rgb), float), stats

    def linear_srgb(self) -> np.ndarray:
        """Linear sRGB (H, W, 3) of XYZ/100 (no exposure, no encoding) — the EXR preview."""
        import colour

        return colour.XYZ_to_sRGB(self.to_xyz() / 100.0, apply_cctf_encoding=False)

    def write_png(self, path, exposure: float = 1.0, colourspace: str = "sRGB", tone_map: str | None = None):
        """8-bit PNG for a display in ``colourspace`` ("sRGB" or "Display P3"; exposure as
        in :meth:`to_srgb`); ``tone_map`` "knee" or "none" through :meth:`to_display`
        (default None: clipped, as :meth:`to_display_rgb`)."""
        from pathlib import Path

        from PIL import Image

        from nmmm.atomic_io import atomic_path

        p = Path(path)
        rgb = (self.to_display_rgb(colourspace, exposure) if tone_map is None
               else self.to_display(colourspace, exposure, tone_map)[0])
        img = Image.fromarray(np.round(rgb * 255).astype(np.uint8))
        with atomic_path(p) as tmp:  # a full disk or a crash leaves no truncated PNG under the name
            img.save(tmp, format="PNG")
        return p

    def write_exr(self, path, half: bool = False):
        """Spectral OpenEXR (Fichet et al. 2021 layout) with an RGB preview."""
        from nmmm.appearance.render.exr import write_spectral_exr

        attrs = {"nmmm": "nmmm.appearance.render"}
        for k, v in self.metadata.items():
            if isinstance(v, (str, int, float)):
                attrs[f"nmmm.{k}"] = v
        return write_spectral_exr(path, self.wavelength_nm, self.radiance, rgb=self.linear_srgb(),
                                  attributes=attrs, half=half)
