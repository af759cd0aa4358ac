"""Spectral OpenEXR files in the layout of Fichet, Pacanowski & Wilkie (2021).

One channel per wavelength, named ``S0.<wavelength>nm`` (Stokes component S0 = radiance)
with a **comma** as decimal separator, e.g. ``S0.380,000000nm``; the header carries
``spectralLayoutVersion = "1.0"`` and ``emissiveUnits`` (``"W.m^-2.sr^-1"``); ``R``, ``G``,
``B`` channels hold a linear sRGB preview so that ordinary viewers show the image.

Public functions
----------------
- :func:`spectral_channel_name` — ``S0.550,000000nm`` for 550 nm.
- :func:`parse_spectral_channel` — inverse (accepts ``.`` or ``,``, any digits).
- :func:`write_spectral_exr` — write (H, W, L) radiance (+ RGB preview) with ``openexr``.
- :func:`read_spectral_exr` — read it back: ``(wavelength_nm, values, rgb, header)``.

References
----------
- A. Fichet, R. Pacanowski, A. Wilkie, "An OpenEXR Layout for Spectral Images", Journal of
  Computer Graphics Techniques 10(3) (2021) 1–18, http://jcgt.org/published/0010/03/01/ ;
  reference implementation https://github.com/afichet/spectral-exr .
- OpenEXR 3 Python bindings (``import OpenEXR``), Academy Software Foundation.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from nmmm.errors import DataFileError, InvalidInputError
from nmmm.spectra import as_wavelength_nm, check_finite

__all__ = ["spectral_channel_name", "parse_spectral_channel", "write_spectral_exr", "read_spectral_exr",
           "EMISSIVE_UNITS"]

EMISSIVE_UNITS = "W.m^-2.sr^-1"
_CHANNEL = re.compile(r"^S([0-3])\.(\d+(?:[.,]\d*)?)nm$")


def spectral_channel_name(wavelength_nm: float, stokes: int = 0) -> str:
    """Fichet et al. (2021) channel name: ``S<stokes>.<λ with 6 decimals, comma>nm``.

    >>> spectral_channel_name(380.0)
    'S0.380,000000nm'
    """
    return f"S{int(stokes)}." + f"{float(wavelength_nm):.6f}".replace(".", ",") + "nm"


def parse_spectral_channel(name: str):
    """``(stokes, wavelength_nm)`` of an emissive spectral channel name, or None."""
    m = _CHANNEL.match(name)
    if m is None:
        return None
    return int(m.group(1)), float(m.group(2).replace(",", "."))


def write_spectral_exr(path, wavelength_nm, values, rgb=None, emissive_units: str = EMISSIVE_UNITS,
                       attributes: dict | None = None, half: bool = False) -> Path:
    """Write a spectral image ``values`` (H, W, L) on ``wavelength_nm`` (L,) to ``path``.

    ``rgb`` (H, W, 3) linear preview (written as R, G, B); ``attributes`` extra string
    header attributes; ``half`` stores 16-bit floats (default 32-bit).
    """
    import OpenEXR

    w = as_wavelength_nm(wavelength_nm).ravel()
    v = np.asarray(check_finite(values, "spectral image"))
    if v.ndim != 3 or v.shape[2] != w.size:
        raise InvalidInputError(f"values must be (height, width, {w.size}) for {w.size} wavelengths, got {v.shape}")
    dt = np.float16 if half else np.float32
    channels = {}
    if rgb is not None:
        c = np.asarray(check_finite(rgb, "rgb preview"))
        if c.shape != v.shape[:2] + (3,):
            raise InvalidInputError(f"rgb preview must be {v.shape[:2] + (3,)}, got {c.shape}")
        for k, name in enumerate("RGB"):
            channels[name] = np.ascontiguousarray(c[..., k], dtype=dt)
    for k, wl in enumerate(w):
        channels[spectral_channel_name(wl)] = np.ascontiguousarray(v[..., k], dtype=dt)
    header = {
        "compression": OpenEXR.ZIP_COMPRESSION,
        "type": OpenEXR.scanlineimage,
        "spectralLayoutVersion": "1.0",
        "emissiveUnits": str(emissive_units),
        "polarisationHandedness": "right",
    }
    for k, val in (attributes or {}).items():
        header[str(k)] = str(val)
    from nmmm.atomic_io import atomic_path

    p = Path(path)
    with atomic_path(p) as tmp, OpenEXR.File(header, channels) as f:  # complete or not there at all
        f.write(str(tmp))
    return p


def read_spectral_exr(path):
    """Read a Fichet-layout spectral EXR: ``(wavelength_nm (L,), values (H, W, L),
    rgb (H, W, 3) or None, header dict)``; channels sorted by wavelength."""
    import OpenEXR

    p = Path(path)
    if not p.is_file():
        raise DataFileError(f"spectral EXR not found: {str(p)!r}")
    try:
        with OpenEXR.File(str(p), separate_channels=True) as f:
            header = dict(f.header())
            chans = {k: np.asarray(c.pixels) for k, c in f.channels().items()}
    except Exception as exc:  # noqa: BLE001 - the binding raises plain exceptions
        raise DataFileError(f"cannot read {str(p)!r} as OpenEXR: {exc}") from exc
    spec = []
    for name in chans:
        parsed = parse_spectral_channel(name)
        if parsed is not None and parsed[0] == 0:
            spec.append((parsed[1], name))
    if not spec:
        raise DataFileError(f"{str(p)!r} has no S0.<wavelength>nm channels (not a Fichet et al. 2021 spectral EXR)")
    spec.sort()
    w = np.array([s[0] for s in spec])
    values = np.stack([chans[s[1]] for s in spec], axis=-1).astype(np.float32)
    rgb = np.stack([chans[c] for c in "RGB"], axis=-1) if all(c in chans for c in "RGB") else None
    return w, values, rgb, header
