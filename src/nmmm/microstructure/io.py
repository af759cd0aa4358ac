"""Save and load microstructures with their units and parameters.

Two compressed standard formats, both read by common tools:

- multi-page TIFF (``.tif``/``.tiff``, zlib-compressed, one page per z slice; the axes
  are stored as (z, y, x) pages as ImageJ/Fiji expect, the metadata as JSON (after the
  prefix ``nmmm.microstructure``) in the ImageDescription tag and the pixel size in the resolution tags, in µm per pixel);
- NumPy ``.npz`` (compressed; ``labels`` plus a ``metadata`` JSON string).

The metadata hold ``voxel_nm``, ``phases``, ``periodic``, ``params`` and ``axes``.

- :func:`save_microstructure` — write a :class:`Microstructure` (format from the suffix),
  atomically: a temporary file beside the target replaces it only when complete, so a full disk
  or a crash never leaves a truncated file under the name (:mod:`nmmm.atomic_io`).
- :func:`load_microstructure` — read it back (files written by other tools load too:
  a TIFF without nmmm metadata gets voxel 1 nm unless ``voxel_nm`` is given).
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from nmmm.atomic_io import atomic_path
from nmmm.errors import DataFileError, InvalidInputError
from nmmm.microstructure.base import Microstructure

__all__ = ["save_microstructure", "load_microstructure"]

_FORMAT = "nmmm.microstructure/1"
#: the JSON in the TIFF description follows this prefix (plain JSON would be taken for
#: tifffile's own "shaped" metadata)
_PREFIX = "nmmm.microstructure "


def _jsonable(o):
    if isinstance(o, dict):
        return {str(k): _jsonable(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_jsonable(v) for v in o]
    if isinstance(o, np.ndarray):
        return o.tolist() if o.size <= 10_000 else f"<array {o.shape}>"
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, float) and not np.isfinite(o):
        return str(o)
    if isinstance(o, (str, int, float, bool)) or o is None:
        return o
    return repr(o)


def _metadata(m: Microstructure) -> dict:
    return {
        "format": _FORMAT,
        "units": "nm",
        "axes": "xyz"[: m.ndim],
        "voxel_nm": list(m.voxel_nm),
        "phases": {str(k): v for k, v in m.phases.items()},
        "periodic": m.periodic,
        "params": _jsonable(m.params),
    }


def save_microstructure(m: Microstructure, path) -> Path:
    """Write ``m`` to ``path`` (.tif/.tiff or .npz), compressed, with metadata; returns the path."""
    if not isinstance(m, Microstructure):
        raise InvalidInputError(f"expected a Microstructure, got {type(m).__name__}")
    p = Path(path)
    meta = _metadata(m)
    suf = p.suffix.lower()
    if suf in (".tif", ".tiff"):
        import tifffile

        lab = np.asarray(m.labels)
        # pages along z; within a page rows = y, columns = x (ImageJ's ZYX order)
        arr = lab.T
        vx, vy = m.voxel_nm[0], m.voxel_nm[1]
        try:
            with atomic_path(p) as tmp:
                tifffile.imwrite(
                    tmp, np.ascontiguousarray(arr), compression="zlib", description=_PREFIX + json.dumps(meta),
                    resolution=(1e3 / vx, 1e3 / vy), resolutionunit=tifffile.RESUNIT.MICROMETER, metadata=None,
                )
        except OSError as exc:
            raise DataFileError(f"cannot write {p}: {exc}") from None
    elif suf == ".npz":
        try:
            with atomic_path(p) as tmp:
                np.savez_compressed(tmp, labels=np.asarray(m.labels), metadata=np.array(json.dumps(meta)))
        except OSError as exc:
            raise DataFileError(f"cannot write {p}: {exc}") from None
    else:
        raise InvalidInputError(f"unknown microstructure file type {suf!r}: use .tif, .tiff or .npz")
    return p


def load_microstructure(path, voxel_nm=None) -> Microstructure:
    """Read a microstructure written by :func:`save_microstructure` (or a plain label TIFF/npz)."""
    p = Path(path)
    if not p.is_file():
        raise DataFileError(f"microstructure file not found: {p}")
    suf = p.suffix.lower()
    meta = None
    try:
        if suf in (".tif", ".tiff"):
            import tifffile

            with tifffile.TiffFile(p) as tf:
                arr = tf.asarray()
                desc = tf.pages[0].description if tf.pages else ""
            try:
                meta = json.loads(desc[len(_PREFIX):]) if desc and desc.startswith(_PREFIX) else None
            except json.JSONDecodeError:
                meta = None
            if meta is not None and meta.get("format") != _FORMAT:
                meta = None
            lab = arr.T if meta is not None else arr
        elif suf == ".npz":
            if not zipfile.is_zipfile(p):
                raise DataFileError(
                    f"cannot read microstructure file {p}: not a .npz (zip) archive; give a file written by "
                    "save_microstructure or numpy.savez with an integer 'labels' array"
                )
            with np.load(p, allow_pickle=False) as z:
                if "labels" not in z:
                    raise DataFileError(f"{p}: no 'labels' array in the .npz file")
                lab = z["labels"]
                meta = json.loads(str(z["metadata"])) if "metadata" in z else None
        else:
            raise DataFileError(f"unknown microstructure file type {suf!r} ({p}): use .tif, .tiff or .npz")
    except DataFileError:
        raise
    except Exception as exc:
        raise DataFileError(f"cannot read microstructure file {p}: {exc}") from None
    if lab.dtype.kind not in "iub":
        raise DataFileError(f"{p}: labels must be integers, got {lab.dtype}")
    if meta is None:
        return Microstructure(lab, voxel_nm if voxel_nm is not None else 1.0, {}, False, {"source": str(p)})
    return Microstructure(
        lab,
        voxel_nm if voxel_nm is not None else tuple(meta["voxel_nm"]),
        {int(k): v for k, v in meta.get("phases", {}).items()},
        bool(meta.get("periodic", True)),
        meta.get("params", {}),
    )
