"""Stimulus pairs of the 2AFC experiment: the ``pairs.toml`` file.

Each *pair* is one computed (rendered) image of a plate and one photograph of the real
plate. A participant sees both, side by side, and picks the photograph.

Public functions and objects
----------------------------
- :class:`ExperimentSettings` — what the participant sees (question, timing, frames, stereo).
- :class:`StimulusPair` — one rendered image and one photograph (and, in stereo mode, the
  left-eye / right-eye views of each).
- :class:`PairSet` — the settings and the pairs of one experiment.
- :func:`load_pairs` — read and validate a ``pairs.toml`` file (every image is opened at load
  time: a missing, unreadable, oversized or mismatched image is a clear error, not a broken
  trial half-way through a session).
- :func:`make_pairs_file` — write a ``pairs.toml`` from ``(rendered_path, photo_path, label)``
  triples, e.g. an nmmm rendering and the photograph of the plate it predicts.
- :func:`check_image` — validate one image file.

The ``pairs.toml`` format
-------------------------
Image paths are relative to the directory that holds the TOML file (absolute paths are
allowed)::

    [experiment]                       # optional table; every key has a default
    title = "Which one is the real plate?"
    question = "Which image is the photograph of the real plate?"
    viewing_distance_cm = 50           # shown in the calibration note
    blank_ms = 1000                    # neutral blank interval before each trial
    repetitions = 1                    # each pair is shown this many times per participant
    stereo = false                     # true: every pair needs *_stereo images
    stereo_arrangement = "parallel"    # "parallel" (L|R, stereoscope) or "cross" (R|L)
    background = "#808080"             # neutral surround and frame colour (sRGB hex)
    frame_px = 24                      # identical neutral frame around both images
    max_image_px = 1024                # longest side of the served images (px)
    consent_text = "..."               # shown before the session starts
    calibration_note = "..."           # display calibration / viewing distance note

    [[pair]]
    id = "hematite-5"                  # optional; defaults to pair-1, pair-2, ...
    label = "Hematite 5 % in epoxy"    # optional; for the experimenter only
    rendered = "renders/hematite5.png" # the computed image
    photo = "photos/hematite5.jpg"     # the photograph of the real plate
    # stereo mode only: [left-eye view, right-eye view]
    rendered_stereo = ["renders/h5_L.png", "renders/h5_R.png"]
    photo_stereo = ["photos/h5_L.jpg", "photos/h5_R.jpg"]

In stereo mode each trial shows two stereo pairs, one above the other (choose top or
bottom); each stereo pair is the left-eye and right-eye view side by side, in their own neutral
frame, for a mirror or lens stereoscope ('parallel': left view on the left) or for cross-eyed
free viewing ('cross').

Within a pair, both images must have the same aspect ratio (within 1 %): a different
shape would tell the participant which image is which. Images are re-encoded to PNG,
converted to sRGB and resampled to a common size when served (see
:mod:`nmmm.experiment.stimuli`), so file format, metadata and pixel size give nothing away.

References
----------
- Macmillan, N. A., Creelman, C. D. (2005). *Detection Theory: A User's Guide*, 2nd ed.,
  Lawrence Erlbaum, ch. 7 (two-alternative forced choice).
"""

from __future__ import annotations

import json
import math
import os
import re
import tomllib
from dataclasses import dataclass, field, fields
from pathlib import Path

from nmmm.errors import DataFileError, InvalidInputError

#: Largest image file accepted (bytes).
MAX_IMAGE_BYTES = 200 * 1024 * 1024
#: Largest image accepted (pixels); Pillow's decompression-bomb guard is set to this.
MAX_IMAGE_PIXELS = 80_000_000

DEFAULT_CONSENT = (
    "You are invited to take part in a short visual experiment. On each trial you will see two "
    "images of a painted plate: one is a photograph of the real plate, the other is computed. "
    "Pick the one you believe is the photograph; if unsure, guess. There are no right answers "
    "you need to know in advance, and you may stop at any time. Your answers and response times "
    "are stored under the participant id you enter, without any other personal data."
)
DEFAULT_CALIBRATION = (
    "Please sit at about {viewing_distance_cm:g} cm from the display, in the room lighting set by "
    "the experimenter. The display should be calibrated to sRGB (D65 white, gamma 2.2); do not "
    "change its brightness, zoom or colour settings during the session."
)

_PAIR_KEYS = ("id", "label", "rendered", "photo", "rendered_stereo", "photo_stereo")
_ID_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")
_COLOUR_RE = re.compile(r"^#[0-9A-Fa-f]{6}$")


@dataclass(frozen=True)
class ExperimentSettings:
    """What the participant sees; every field has a sensible default."""

    title: str = "Which one is the real plate?"
    question: str = "Which image is the photograph of the real plate?"
    viewing_distance_cm: float = 50.0
    blank_ms: int = 1000
    repetitions: int = 1
    stereo: bool = False
    stereo_arrangement: str = "parallel"
    background: str = "#808080"
    frame_px: int = 24
    max_image_px: int = 1024
    consent_text: str = DEFAULT_CONSENT
    calibration_note: str = DEFAULT_CALIBRATION

    def __post_init__(self):
        checks = [
            (isinstance(self.title, str) and self.title.strip() != "", "title", "a non-empty string"),
            (isinstance(self.question, str) and self.question.strip() != "", "question", "a non-empty string"),
            (_is_number(self.viewing_distance_cm) and 10 <= self.viewing_distance_cm <= 1000,
             "viewing_distance_cm", "a number of centimetres in [10, 1000]"),
            (_is_int(self.blank_ms) and 0 <= self.blank_ms <= 60_000, "blank_ms", "an integer in [0, 60000]"),
            (_is_int(self.repetitions) and 1 <= self.repetitions <= 100, "repetitions", "an integer in [1, 100]"),
            (isinstance(self.stereo, bool), "stereo", "true or false"),
            (self.stereo_arrangement in ("parallel", "cross"), "stereo_arrangement", "'parallel' or 'cross'"),
            (isinstance(self.background, str) and bool(_COLOUR_RE.match(self.background)),
             "background", "an sRGB hex colour such as '#808080'"),
            (_is_int(self.frame_px) and 0 <= self.frame_px <= 500, "frame_px", "an integer in [0, 500]"),
            (_is_int(self.max_image_px) and 16 <= self.max_image_px <= 8192, "max_image_px",
             "an integer in [16, 8192]"),
            (isinstance(self.consent_text, str) and self.consent_text.strip() != "", "consent_text",
             "a non-empty string"),
            (isinstance(self.calibration_note, str), "calibration_note", "a string"),
        ]
        for ok, name, right in checks:
            if not ok:
                raise InvalidInputError(f"experiment setting {name!r} = {getattr(self, name)!r} is invalid; "
                                        f"expected {right}")

    def calibration_text(self) -> str:
        """The calibration note with ``{viewing_distance_cm}`` filled in."""
        try:
            return self.calibration_note.format(viewing_distance_cm=self.viewing_distance_cm)
        except (KeyError, IndexError, ValueError):
            return self.calibration_note


@dataclass(frozen=True)
class StimulusPair:
    """One rendered image and one photograph of the same plate (absolute paths).

    ``rendered_stereo`` and ``photo_stereo`` are ``(left_eye, right_eye)`` paths or ``None``.
    """

    pair_id: str
    label: str
    rendered: Path
    photo: Path
    rendered_stereo: tuple[Path, Path] | None = None
    photo_stereo: tuple[Path, Path] | None = None

    def image(self, role: str, eye: str | None = None) -> Path:
        """The path of ``role`` ('rendered' or 'photo'), for ``eye`` None, 'left' or 'right'."""
        if role not in ("rendered", "photo"):
            raise InvalidInputError(f"role must be 'rendered' or 'photo', got {role!r}")
        if eye is None:
            return getattr(self, role)
        views = getattr(self, f"{role}_stereo")
        if views is None:
            raise InvalidInputError(f"pair {self.pair_id!r} has no stereo views")
        if eye not in ("left", "right"):
            raise InvalidInputError(f"eye must be 'left' or 'right', got {eye!r}")
        return views[0 if eye == "left" else 1]


@dataclass(frozen=True)
class PairSet:
    """The settings and the stimulus pairs of one experiment."""

    settings: ExperimentSettings
    pairs: tuple[StimulusPair, ...]
    source: Path | None = None
    _index: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self):
        if not self.pairs:
            raise InvalidInputError("an experiment needs at least one pair")
        ids = [p.pair_id for p in self.pairs]
        dup = sorted({i for i in ids if ids.count(i) > 1})
        if dup:
            raise InvalidInputError(f"pair ids must be unique; repeated: {dup}")
        self._index.update({p.pair_id: p for p in self.pairs})

    @property
    def n_trials(self) -> int:
        """Trials per participant: pairs times repetitions."""
        return len(self.pairs) * self.settings.repetitions

    def __getitem__(self, pair_id: str) -> StimulusPair:
        try:
            return self._index[pair_id]
        except KeyError:
            raise InvalidInputError(f"unknown pair id {pair_id!r}; known: {sorted(self._index)}") from None

    def __len__(self) -> int:
        return len(self.pairs)


def _is_int(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def check_image(path, *, max_bytes: int = MAX_IMAGE_BYTES, max_pixels: int = MAX_IMAGE_PIXELS,
                what: str = "image") -> tuple[int, int]:
    """Check that ``path`` is a readable image of acceptable size; return ``(width, height)``
    as displayed (after the EXIF orientation).

    Raises
    ------
    DataFileError
        The file is missing, is not an image Pillow can decode, is larger than ``max_bytes``
        or has more than ``max_pixels`` pixels.
    """
    from PIL import Image, UnidentifiedImageError

    path = Path(path)
    if not path.is_file():
        raise DataFileError(f"{what} {str(path)!r} not found (no such file)")
    size = path.stat().st_size
    if size > max_bytes:
        raise DataFileError(f"{what} {str(path)!r} is {size / 2**20:.1f} MiB; at most "
                            f"{max_bytes / 2**20:.1f} MiB is accepted (downscale or compress it)")
    if size == 0:
        raise DataFileError(f"{what} {str(path)!r} is empty; expected a PNG, JPEG or TIFF image")
    try:
        with Image.open(path) as im:
            width, height = im.size
            if width * height > max_pixels:
                raise DataFileError(f"{what} {str(path)!r} has {width}x{height} = {width * height} pixels; "
                                    f"at most {max_pixels} are accepted (downscale it)")
            im.verify()
        with Image.open(path) as im:  # a camera's EXIF orientation: shown (and served) rotated
            if im.getexif().get(0x0112, 1) in (5, 6, 7, 8):
                width, height = height, width
    except DataFileError:
        raise
    except (UnidentifiedImageError, Image.DecompressionBombError, OSError, SyntaxError, ValueError,
            RuntimeError) as exc:
        raise DataFileError(f"{what} {str(path)!r} is not an image that can be read "
                            f"(expected PNG, JPEG, TIFF or WebP): {exc}") from None
    return width, height


def _load_toml(path: Path) -> dict:
    if not path.is_file():
        raise DataFileError(f"pairs file {str(path)!r} not found")
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise DataFileError(f"pairs file {str(path)!r} is not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise DataFileError(f"pairs file {str(path)!r} is not UTF-8 text: {exc}") from None


def load_pairs(path, *, check_images: bool = True, max_bytes: int = MAX_IMAGE_BYTES,
               max_pixels: int = MAX_IMAGE_PIXELS) -> PairSet:
    """Read and validate a ``pairs.toml`` file (format in the module docstring).

    Every image is opened now, so that a missing or unreadable image is reported before any
    participant starts. Within each pair the rendered image and the photograph (and each
    stereo view) must share one aspect ratio, within 1 %.

    Raises
    ------
    DataFileError
        Missing or malformed TOML, an unknown or missing key (the message names the pair and
        key), a missing, non-image or oversized image, or mismatched aspect ratios.
    """
    path = Path(path).resolve()
    data = _load_toml(path)
    base = path.parent
    where = f"pairs file {str(path)!r}"

    unknown = sorted(set(data) - {"experiment", "pair"})
    if unknown:
        raise DataFileError(f"{where}: unknown top-level key(s) {unknown}; expected an optional "
                            f"[experiment] table and [[pair]] entries")
    exp = data.get("experiment", {})
    if not isinstance(exp, dict):
        raise DataFileError(f"{where}: 'experiment' must be a table ([experiment])")
    valid = [f.name for f in fields(ExperimentSettings)]
    bad = sorted(set(exp) - set(valid))
    if bad:
        raise DataFileError(f"{where}: unknown [experiment] key(s) {bad}; valid keys: {valid}")
    try:
        settings = ExperimentSettings(**exp)
    except InvalidInputError as exc:
        raise DataFileError(f"{where}: {exc}") from None

    raw_pairs = data.get("pair")
    if not raw_pairs:
        raise DataFileError(f"{where}: no [[pair]] entries; each needs 'rendered' and 'photo' image paths")
    if not isinstance(raw_pairs, list) or not all(isinstance(p, dict) for p in raw_pairs):
        raise DataFileError(f"{where}: 'pair' must be an array of tables ([[pair]])")

    def resolve(value, key, name):
        if not isinstance(value, str) or not value:
            raise DataFileError(f"{where}: {name}: {key!r} must be an image path (string), got {value!r}")
        p = Path(value)
        return (p if p.is_absolute() else base / p).resolve()

    pairs, seen = [], set()
    for i, raw in enumerate(raw_pairs, start=1):
        pair_id = raw.get("id", f"pair-{i}")
        name = f"pair {i} (id {pair_id!r})"
        bad = sorted(set(raw) - set(_PAIR_KEYS))
        if bad:
            raise DataFileError(f"{where}: {name}: unknown key(s) {bad}; valid keys: {list(_PAIR_KEYS)}")
        if not isinstance(pair_id, str) or not _ID_RE.match(pair_id):
            raise DataFileError(f"{where}: {name}: 'id' must be 1-64 characters from letters, digits, "
                                f"'.', '_', '-' (starting with a letter or digit)")
        if pair_id in seen:
            raise DataFileError(f"{where}: {name}: id {pair_id!r} is used twice; pair ids must be unique")
        seen.add(pair_id)
        label = raw.get("label", pair_id)
        if not isinstance(label, str):
            raise DataFileError(f"{where}: {name}: 'label' must be a string")
        for key in ("rendered", "photo"):
            if key not in raw:
                raise DataFileError(f"{where}: {name}: missing {key!r} (path of the "
                                    f"{'computed image' if key == 'rendered' else 'photograph'})")
        rendered = resolve(raw["rendered"], "rendered", name)
        photo = resolve(raw["photo"], "photo", name)
        stereo = {}
        for key in ("rendered_stereo", "photo_stereo"):
            if key in raw:
                v = raw[key]
                if not (isinstance(v, list) and len(v) == 2):
                    raise DataFileError(f"{where}: {name}: {key!r} must be [left_eye_path, right_eye_path]")
                stereo[key] = (resolve(v[0], key, name), resolve(v[1], key, name))
            elif settings.stereo:
                raise DataFileError(f"{where}: {name}: stereo = true needs {key!r} = "
                                    f"[left_eye_path, right_eye_path]")
        pair = StimulusPair(pair_id, label, rendered, photo,
                            stereo.get("rendered_stereo"), stereo.get("photo_stereo"))
        pairs.append((pair, name, stereo))
    for pair, name, stereo in pairs:  # after the whole file's keys and ids are known good
        _check_distinct_images(pair.rendered, pair.photo, stereo, name, where)
        if check_images:
            _check_pair_images(pair, name, where, max_bytes, max_pixels)
    return PairSet(settings, tuple(p for p, _, _ in pairs), source=path)


def _same_file(a: Path, b: Path) -> bool:
    """True when ``a`` and ``b`` are one file (same path, a link to it) or byte-identical copies."""
    if a == b:
        return True
    try:
        if a.exists() and b.exists():
            if a.samefile(b):
                return True
            sa, sb = a.stat().st_size, b.stat().st_size
            if sa == sb and sa <= MAX_IMAGE_BYTES:
                return a.read_bytes() == b.read_bytes()
    except OSError:
        return False
    return False


def _check_distinct_images(rendered: Path, photo: Path, stereo: dict, name, where):
    """A pair whose computed image is the photograph measures nothing: refuse it (issue 21)."""
    checks = [("rendered", rendered, "photo", photo)]
    if "rendered_stereo" in stereo and "photo_stereo" in stereo:
        for j in (0, 1):
            checks.append((f"rendered_stereo[{j}]", stereo["rendered_stereo"][j],
                           f"photo_stereo[{j}]", stereo["photo_stereo"][j]))
    for ka, a, kb, b in checks:
        if _same_file(a, b):
            raise DataFileError(f"{where}: {name}: {ka!r} and {kb!r} are the same image ({b.name}); a pair needs "
                                "the computed image and a photograph of the real plate, two different files")


def _check_pair_images(pair: StimulusPair, name, where, max_bytes, max_pixels):
    groups = [[("rendered", pair.rendered), ("photo", pair.photo)]]
    if pair.rendered_stereo and pair.photo_stereo:
        groups.append([("rendered_stereo[0]", pair.rendered_stereo[0]), ("photo_stereo[0]", pair.photo_stereo[0]),
                       ("rendered_stereo[1]", pair.rendered_stereo[1]), ("photo_stereo[1]", pair.photo_stereo[1])])
    elif pair.rendered_stereo or pair.photo_stereo:
        raise DataFileError(f"{where}: {name}: give both 'rendered_stereo' and 'photo_stereo', or neither")
    for group in groups:
        shapes = []
        for key, p in group:
            try:
                shapes.append((key, check_image(p, max_bytes=max_bytes, max_pixels=max_pixels,
                                                what=f"{key} image")))
            except DataFileError as exc:
                hint = " (paths are relative to the directory of the pairs file)" if "not found" in str(exc) else ""
                raise DataFileError(f"{where}: {name}: {exc}{hint}") from None
        ratios = [(key, w / h) for key, (w, h) in shapes]
        r0 = ratios[0][1]
        for key, r in ratios[1:]:
            if abs(r / r0 - 1) > 0.01:
                dims = ", ".join(f"{k} {w}x{h}" for k, (w, h) in shapes)
                raise DataFileError(f"{where}: {name}: images have different aspect ratios ({dims}); a "
                                    f"different shape would give the photograph away: crop them to one "
                                    f"aspect ratio")


def _slug(text: str) -> str:
    s = re.sub(r"[^A-Za-z0-9._-]+", "-", text).strip("-._")[:48]
    return s or "pair"


def _toml_str(s: str) -> str:
    # JSON string escapes are a subset of TOML basic-string escapes.
    return json.dumps(str(s), ensure_ascii=False)


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    return _toml_str(v)


def _write_array_png(image, path: Path, name: str) -> Path:
    """Write an sRGB-encoded image array (floats in [0, 1] or uint8) as an 8-bit PNG."""
    import numpy as np
    from PIL import Image

    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] not in (3, 4) or a.dtype.kind not in "uf":
        raise InvalidInputError(f"{name}: a rendered image array must be (height, width, 3) floats in [0, 1] "
                                f"or uint8 (sRGB-encoded), got shape {a.shape} dtype {a.dtype}")
    if a.dtype.kind == "f":
        if not np.all(np.isfinite(a)) or a.min() < 0 or a.max() > 1:
            raise InvalidInputError(f"{name}: rendered image values must be finite and in [0, 1] (sRGB-encoded; "
                                    f"tone-map or clip first), got range [{np.nanmin(a):.3g}, {np.nanmax(a):.3g}]")
        a = np.round(a * 255)
    elif a.dtype != np.uint8:
        raise InvalidInputError(f"{name}: integer rendered images must be uint8, got {a.dtype}")
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(a[..., :3].astype(np.uint8), "RGB").save(path)
    return path


def make_pairs_file(pairs, out_toml, *, stereo_pairs=None, check_images: bool = True,
                    **settings) -> Path:
    """Write a ``pairs.toml`` for the 2AFC experiment and return its path.

    Parameters
    ----------
    pairs : iterable of (rendered, photo_path, label)
        The computed image, the photograph of the same real plate, and a label for the
        experimenter (it becomes the pair id after slugification, made unique). ``rendered``
        is an image path, or an sRGB-encoded image array (H, W, 3) — floats in [0, 1] or
        uint8 — which is written as ``<out_toml dir>/rendered/<pair id>.png``.
    out_toml : path
        The file to write; image paths are written relative to its directory where possible.
    stereo_pairs : iterable of ((rendered_left, rendered_right), (photo_left, photo_right)), optional
        Stereo views, one entry per pair, in the same order (needed with ``stereo=True``).
    check_images : bool
        Validate the written file with :func:`load_pairs` (default), so that a missing image is
        reported now.
    **settings
        Keys of the ``[experiment]`` table (see :class:`ExperimentSettings`), e.g.
        ``repetitions=2, viewing_distance_cm=60``.

    Examples
    --------
    >>> make_pairs_file([("render/h5.png", "photos/h5.jpg", "hematite 5 %")],
    ...                 "pairs.toml")  # doctest: +SKIP
    """
    out = Path(out_toml).resolve()
    base = out.parent
    valid = {f.name for f in fields(ExperimentSettings)}
    bad = sorted(set(settings) - valid)
    if bad:
        raise InvalidInputError(f"unknown experiment setting(s) {bad}; valid: {sorted(valid)}")
    ExperimentSettings(**settings)  # validate now
    pairs = list(pairs)
    if not pairs:
        raise InvalidInputError("make_pairs_file needs at least one (rendered_path, photo_path, label)")
    stereo_pairs = list(stereo_pairs) if stereo_pairs is not None else None
    if stereo_pairs is not None and len(stereo_pairs) != len(pairs):
        raise InvalidInputError(f"stereo_pairs has {len(stereo_pairs)} entries for {len(pairs)} pairs")

    def rel(p) -> str:
        p = Path(p).resolve()
        try:
            return os.path.relpath(p, base).replace(os.sep, "/")
        except ValueError:  # another drive on Windows
            return str(p)

    lines = ["# 2AFC validation experiment: which image is the photograph of the real plate?",
             "# Written by nmmm.experiment.make_pairs_file; paths are relative to this file.", ""]
    if settings:
        lines.append("[experiment]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in settings.items()]
        lines.append("")
    used = set()
    for i, item in enumerate(pairs):
        try:
            rendered, photo, label = item
        except (TypeError, ValueError):
            raise InvalidInputError(f"pair {i + 1}: expected (rendered_path, photo_path, label), got {item!r}") from None
        pid = base_id = _slug(str(label))
        n = 2
        while pid in used:
            pid, n = f"{base_id}-{n}", n + 1
        used.add(pid)
        if not isinstance(rendered, (str, os.PathLike)):
            rendered = _write_array_png(rendered, base / "rendered" / f"{pid}.png", f"pair {i + 1} ({label!r})")
        lines += ["[[pair]]", f"id = {_toml_str(pid)}", f"label = {_toml_str(label)}",
                  f"rendered = {_toml_str(rel(rendered))}", f"photo = {_toml_str(rel(photo))}"]
        if stereo_pairs is not None:
            (rl, rr), (pl, pr) = stereo_pairs[i]
            lines += [f"rendered_stereo = [{_toml_str(rel(rl))}, {_toml_str(rel(rr))}]",
                      f"photo_stereo = [{_toml_str(rel(pl))}, {_toml_str(rel(pr))}]"]
        lines.append("")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines), encoding="utf-8")
    if check_images:
        load_pairs(out)
    return out


__all__ = ["ExperimentSettings", "StimulusPair", "PairSet", "load_pairs", "make_pairs_file", "check_image",
           "MAX_IMAGE_BYTES", "MAX_IMAGE_PIXELS"]
