"""Prepare the images that participants see, so that nothing but appearance differs.

- :func:`prepare_image` — decode an image, convert it to 8-bit sRGB (through its embedded ICC
  profile, if any), resample it to a given size, and re-encode it as a metadata-free PNG.
- :class:`StimulusStore` — all stimuli of a :class:`~nmmm.experiment.pairs.PairSet`, prepared
  once at server start into a cache directory under opaque file names.

Why: a photograph straight from a camera differs from a rendering in ways that have nothing
to do with appearance — JPEG vs PNG, EXIF and ICC metadata, pixel size. Any of them, visible
in the browser or the network tab, would let a participant find the photograph without
looking. Both images of a pair are therefore served in one format, one colour space and one
pixel size (the smaller of the two, capped at ``max_image_px`` on the longest side).

References
----------
- IEC 61966-2-1:1999, Multimedia systems and equipment — Colour measurement and management —
  Part 2-1: Default RGB colour space — sRGB.
"""

from __future__ import annotations

import io
import secrets
from pathlib import Path

import numpy as np

from nmmm.errors import DataFileError


def _to_rgb8(im):
    """Return an 8-bit RGB Pillow image in sRGB."""
    from PIL import Image, ImageCms

    icc = im.info.get("icc_profile")
    if im.mode in ("I;16", "I;16B", "I;16L", "I", "F"):
        a = np.asarray(im, dtype=np.float64)
        top = 65535.0 if im.mode.startswith("I;16") or a.max() > 255 else 255.0
        if im.mode == "F":
            top = max(float(np.nanmax(a)), 1e-12) if np.nanmax(a) > 1 else 1.0
        a = np.clip(np.nan_to_num(a / top), 0, 1)
        im = Image.fromarray(np.round(a * 255).astype(np.uint8), "L")
    if im.mode in ("RGBA", "LA", "PA") or (im.mode == "P" and "transparency" in im.info):
        im = im.convert("RGBA")
        bg = Image.new("RGBA", im.size, (128, 128, 128, 255))  # neutral grey under transparency
        im = Image.alpha_composite(bg, im)
    if icc:
        try:
            src = ImageCms.ImageCmsProfile(io.BytesIO(icc))
            dst = ImageCms.createProfile("sRGB")
            if im.mode not in ("RGB", "L", "CMYK"):
                im = im.convert("RGB")
            im = ImageCms.profileToProfile(im, src, dst, outputMode="RGB")
        except (ImageCms.PyCMSError, OSError, ValueError) as exc:
            raise DataFileError(f"cannot apply the embedded ICC colour profile: {exc}") from None
    return im.convert("RGB")


def prepare_image(path, size: tuple[int, int]) -> bytes:
    """Decode ``path``, convert to 8-bit sRGB, resample to ``size`` (width, height); return PNG bytes.

    The PNG carries no metadata (no EXIF, no ICC profile, no text chunks): its pixels are
    sRGB, the browser's default.
    """
    from PIL import Image, ImageOps

    try:
        with Image.open(path) as im:
            im = ImageOps.exif_transpose(im)
            im.load()
            rgb = _to_rgb8(im)
    except DataFileError as exc:
        raise DataFileError(f"image {str(path)!r}: {exc}") from None
    except (OSError, ValueError, SyntaxError) as exc:
        raise DataFileError(f"image {str(path)!r} cannot be decoded: {exc}") from None
    if rgb.size != tuple(size):
        rgb = rgb.resize(tuple(size), Image.Resampling.LANCZOS, reducing_gap=3.0)
    rgb.info = {}  # no ICC profile, EXIF or text chunks: the pixels are sRGB, the browser's default
    buf = io.BytesIO()
    rgb.save(buf, format="PNG", optimize=False, compress_level=6)
    return buf.getvalue()


def _common_size(paths, max_px: int) -> tuple[int, int]:
    from PIL import Image, ImageOps

    sizes = []
    for p in paths:
        with Image.open(p) as im:
            w, h = im.size
            orientation = im.getexif().get(0x0112, 1) if hasattr(im, "getexif") else 1
            if orientation in (5, 6, 7, 8):
                w, h = h, w
            sizes.append((w, h))
    w, h = min(sizes, key=lambda s: s[0] * s[1])
    scale = min(1.0, max_px / max(w, h))
    return max(1, round(w * scale)), max(1, round(h * scale))


class StimulusStore:
    """The prepared stimuli of one experiment, keyed by ``(pair_id, role, eye)``.

    ``role`` is 'rendered' or 'photo'; ``eye`` is None (mono), 'left' or 'right'. Files are
    written once into ``cache_dir`` under random names; :meth:`path` returns them.
    """

    def __init__(self, pairset, cache_dir, progress: bool = False):
        self.cache_dir = Path(cache_dir)
        self.cache_dir.mkdir(parents=True, exist_ok=True)
        self._files: dict[tuple, Path] = {}
        self.sizes: dict[tuple, tuple[int, int]] = {}
        max_px = pairset.settings.max_image_px
        jobs = []
        for pair in pairset.pairs:
            groups = [(None, [("rendered", pair.rendered), ("photo", pair.photo)])]
            if pairset.settings.stereo:
                for k, eye in enumerate(("left", "right")):
                    groups.append((eye, [("rendered", pair.rendered_stereo[k]), ("photo", pair.photo_stereo[k])]))
            for eye, items in groups:
                size = _common_size([p for _, p in items], max_px)
                for role, p in items:
                    jobs.append(((pair.pair_id, role, eye), p, size))
        iterator = jobs
        if progress:
            from tqdm import tqdm

            iterator = tqdm(jobs, desc="preparing stimuli", unit="image")
        for key, p, size in iterator:
            data = prepare_image(p, size)
            out = self.cache_dir / f"{secrets.token_hex(12)}.png"
            out.write_bytes(data)
            self._files[key] = out
            self.sizes[key] = size

    def path(self, pair_id: str, role: str, eye: str | None = None) -> Path:
        """The prepared PNG of ``(pair_id, role, eye)``."""
        return self._files[(pair_id, role, eye)]

    def size(self, pair_id: str, eye: str | None = None) -> tuple[int, int]:
        """The common (width, height) of both images of a pair (one eye in stereo)."""
        return self.sizes[(pair_id, "photo", eye)]


__all__ = ["prepare_image", "StimulusStore"]
