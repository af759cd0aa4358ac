"""Prepare the images that participants see, so that nothing but the pixels differs.

- :func:`prepare_pixels` — decode an image, convert it to 8-bit sRGB (through its embedded ICC
  profile, if any) and resample it to a given size: an ``(height, width, 3)`` uint8 array.
- :func:`prepare_image` — the same, re-encoded as a metadata-free PNG (for figures and tools;
  the server does not send PNGs, whose length depends on the content).
- :func:`encode_bmp` — an uncompressed 24-bit BMP whose length depends only on the pixel size.
- :class:`StimulusStore` — all stimuli of a :class:`~nmmm.experiment.pairs.PairSet`, prepared
  once into memory, with a content-addressed cache on disk (:func:`default_cache_dir`) that a
  restarted server reuses instead of preparing them again.

Why: a photograph straight from a camera differs from a rendering in ways that have nothing
to do with appearance — JPEG vs PNG, EXIF and ICC metadata, pixel size, and (even after
re-encoding both to PNG) the compressed size, since a noisy photograph compresses worse than
a smooth rendering. Any of them, visible in the browser's network tab, would let a
participant find the photograph without looking. Both images of a pair are therefore
converted to one colour space and one pixel size (the smaller of the two, capped at
``max_image_px`` on the longest side; in stereo mode all four views share it), and served
*uncompressed*: raw RGB bytes (one response per trial carrying every view, see
:mod:`nmmm.experiment.app`) or an uncompressed BMP. The number of bytes is ``3 × width ×
height`` per view whatever the pixels are, so the length of what is sent cannot tell the
photograph from the rendering: this holds by construction, not by measurement.

References
----------
- IEC 61966-2-1:1999, Multimedia systems and equipment — Colour measurement and management —
  Part 2-1: Default RGB colour space — sRGB.
- Microsoft, "BITMAPINFOHEADER structure" (Win32 GDI documentation): the 40-byte header of an
  uncompressed (BI_RGB) bitmap.
"""

from __future__ import annotations

import hashlib
import io
import os
import secrets
import struct
from pathlib import Path

import numpy as np

from nmmm.errors import DataFileError

#: Version of the preparation (decoding, colour conversion, resampling); part of every cache key,
#: so a change of the preparation never reuses stimuli prepared the old way.
PREPARATION_VERSION = "2"
_DIGEST = 32  # sha256 of the pixels, appended to every cached file and checked when it is read


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


def prepare_pixels(path, size: tuple[int, int]) -> np.ndarray:
    """Decode ``path``, convert to 8-bit sRGB, resample to ``size`` (width, height).

    Returns a C-contiguous ``(height, width, 3)`` uint8 array of sRGB values (the EXIF
    orientation applied, transparency composited over neutral grey, an embedded ICC profile
    converted to sRGB).
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
    return np.ascontiguousarray(np.asarray(rgb, dtype=np.uint8))


def prepare_image(path, size: tuple[int, int]) -> bytes:
    """Decode ``path``, convert to 8-bit sRGB, resample to ``size`` (width, height); return PNG bytes.

    The PNG carries no metadata (no EXIF, no ICC profile, no text chunks): its pixels are
    sRGB, the browser's default. (Its length depends on the content: the experiment server
    sends :func:`prepare_pixels` uncompressed instead.)
    """
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(prepare_pixels(path, size), "RGB").save(buf, format="PNG", optimize=False, compress_level=6)
    return buf.getvalue()


def bmp_length(width: int, height: int) -> int:
    """Bytes of the uncompressed 24-bit BMP of :func:`encode_bmp`: ``54 + height * stride``."""
    return 54 + int(height) * ((3 * int(width) + 3) // 4 * 4)


def encode_bmp(rgb) -> bytes:
    """An uncompressed 24-bit BMP (BITMAPINFOHEADER, BI_RGB, no colour table, no resolution,
    bottom-up rows padded to 4 bytes) of an ``(height, width, 3)`` uint8 sRGB array.

    Every field of the 54-byte header follows from the pixel size alone, so two images of one
    size give files of the same length that differ only in their pixel bytes.
    """
    a = np.asarray(rgb)
    if a.ndim != 3 or a.shape[2] != 3 or a.dtype != np.uint8:
        raise DataFileError(f"encode_bmp needs a (height, width, 3) uint8 array, got {a.shape} {a.dtype}")
    h, w = a.shape[:2]
    stride = (3 * w + 3) // 4 * 4
    rows = np.zeros((h, stride), np.uint8)
    rows[:, : 3 * w] = a[::-1, :, ::-1].reshape(h, 3 * w)   # bottom-up, BGR
    size = 54 + rows.size
    header = struct.pack("<2sIHHI", b"BM", size, 0, 0, 54) + struct.pack(
        "<IiiHHIIiiII", 40, w, h, 1, 24, 0, rows.size, 0, 0, 0, 0)
    return header + rows.tobytes()


def _common_size(paths, max_px: int) -> tuple[int, int]:
    from PIL import Image

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


def default_cache_dir() -> Path:
    """Where prepared stimuli are cached between server runs: ``$NMMM_STIMULUS_CACHE``, else
    ``$XDG_CACHE_HOME/nmmm/stimuli``, else ``~/.cache/nmmm/stimuli``.

    The cache is content-addressed (the key is the SHA-256 of the source file, the served size
    and :data:`PREPARATION_VERSION`), so one folder serves every experiment and a stale entry can
    never be served for a changed image.
    """
    env = os.environ.get("NMMM_STIMULUS_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "nmmm" / "stimuli"


def _sha256_file(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


class StimulusStore:
    """The prepared stimuli of one experiment, in memory, keyed by ``(pair_id, role, eye)``.

    ``role`` is 'rendered' or 'photo'; ``eye`` is None (mono) or 'left' / 'right' (stereo mode:
    only the stereo views are served). All views of one pair share one pixel size. Each view is
    kept as raw RGB bytes (``3 × width × height``) and as an uncompressed BMP of one length.

    ``cache_dir`` (None: no disk cache) holds the prepared pixels under content-addressed names
    (``<sha256 key>.rgb``: the pixels and the SHA-256 of the pixels, checked when read); a
    restarted server reads them back instead of decoding and resampling the images again.
    ``counts`` says how many views were ``prepared`` and how many ``reused`` from the cache.
    """

    def __init__(self, pairset, cache_dir=None, progress: bool = False):
        self.cache_dir = None if cache_dir is None else Path(cache_dir)
        if self.cache_dir is not None:
            try:
                self.cache_dir.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise DataFileError(f"cannot create the stimulus cache {str(self.cache_dir)!r}: {exc}; "
                                    f"give a writable --cache-dir or set NMMM_STIMULUS_CACHE") from None
        self.stereo = bool(pairset.settings.stereo)
        self.eyes = ("left", "right") if self.stereo else (None,)
        self._raw: dict[tuple, bytes] = {}
        self._bmp: dict[tuple, bytes] = {}
        self.sizes: dict[str, tuple[int, int]] = {}
        self.counts = {"prepared": 0, "reused": 0}
        max_px = pairset.settings.max_image_px
        jobs = []
        for pair in pairset.pairs:
            views = [(role, eye, pair.image(role, eye)) for eye in self.eyes for role in ("rendered", "photo")]
            size = _common_size([p for _, _, p in views], max_px)
            self.sizes[pair.pair_id] = size
            jobs += [((pair.pair_id, role, eye), p, size) for role, eye, p in views]
        iterator = jobs
        if progress:
            from tqdm import tqdm

            iterator = tqdm(jobs, desc="preparing stimuli", unit="image")
        for key, p, size in iterator:
            raw = self._load(p, size)
            self._raw[key] = raw
            w, h = size
            self._bmp[key] = encode_bmp(np.frombuffer(raw, np.uint8).reshape(h, w, 3))

    # -- the content-addressed disk cache ------------------------------------------------
    def _load(self, path, size) -> bytes:
        w, h = size
        n = 3 * w * h
        entry = None
        if self.cache_dir is not None:
            key = hashlib.sha256(f"{PREPARATION_VERSION}|{_sha256_file(path)}|{w}x{h}".encode()).hexdigest()
            entry = self.cache_dir / f"{key}.rgb"
            try:
                data = entry.read_bytes()
            except OSError:
                data = b""
            if len(data) == n + _DIGEST and hashlib.sha256(data[:n]).digest() == data[n:]:
                self.counts["reused"] += 1
                return data[:n]
        raw = prepare_pixels(path, size).tobytes()
        self.counts["prepared"] += 1
        if entry is not None:
            tmp = entry.with_name(f".{entry.name}.{secrets.token_hex(6)}.tmp")
            try:
                tmp.write_bytes(raw + hashlib.sha256(raw).digest())
                os.replace(tmp, entry)   # atomic: a killed server never leaves a half-written entry
            except OSError:
                tmp.unlink(missing_ok=True)   # a full or read-only cache only costs time at the next start
        return raw

    # -- what the server sends ---------------------------------------------------------
    def size(self, pair_id: str, eye: str | None = None) -> tuple[int, int]:
        """The common (width, height) of every view of a pair."""
        return self.sizes[pair_id]

    def raw(self, pair_id: str, role: str, eye: str | None = None) -> bytes:
        """The raw RGB bytes (rows top to bottom, ``3 × width × height``) of one view."""
        return self._raw[(pair_id, role, eye)]

    def bmp(self, pair_id: str, role: str, eye: str | None = None) -> bytes:
        """The uncompressed BMP of one view (its length depends on the pixel size only)."""
        return self._bmp[(pair_id, role, eye)]

    def trial_views(self, photo_slot: int) -> list[tuple[int, str | None, str]]:
        """``(slot, eye, role)`` of the views of a trial, in the order they are sent."""
        roles = ("photo", "rendered") if photo_slot == 0 else ("rendered", "photo")
        return [(slot, eye, roles[slot]) for slot in (0, 1) for eye in self.eyes]

    def trial_body(self, pair_id: str, photo_slot: int) -> bytes:
        """Every view of a trial in one body: the raw RGB bytes of slot 0 then slot 1 (left then
        right, or top then bottom; in stereo mode the left-eye then the right-eye view of each).

        Its length, ``n_views × 3 × width × height``, does not depend on ``photo_slot``.
        """
        return b"".join(self._raw[(pair_id, role, eye)] for _, eye, role in self.trial_views(photo_slot))


__all__ = ["prepare_pixels", "prepare_image", "encode_bmp", "bmp_length", "default_cache_dir", "StimulusStore",
           "PREPARATION_VERSION"]
