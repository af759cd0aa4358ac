"""Transmittance of a thick, homogeneous plate in air (incoherent: no interference fringes).

- :func:`plate_transmittance` — Beer–Lambert absorption α = 4πk/λ inside, the Fresnel losses of
  the two faces at normal incidence, and (by default) the incoherent sum of the multiple
  reflections between them.

Used for glasses such as the seed paper's gold-ruby glass (a plate of an effective medium) by
``[plate]`` recipes and the demo.

References
----------
- M. Born, E. Wolf, Principles of Optics, 7th ed., Cambridge University Press (1999), §1.5
  (Fresnel, normal incidence), §14.1 (absorbing media).
"""

from __future__ import annotations

import numpy as np

from nmmm.spectra import as_wavelength_nm, check_nk, check_positive

__all__ = ["plate_transmittance"]


def plate_transmittance(nk, wavelength_nm, thickness_nm, multiple_reflections: bool = True) -> np.ndarray:
    """Transmittance of a plate of index ``nk`` in air at normal incidence.

    ``T = (1 − R)² e^{−α d} / (1 − R² e^{−2 α d})`` with ``R = |(N − 1)/(N + 1)|²`` and
    ``α = 4π k / λ`` (incoherent multiple reflections; with ``multiple_reflections=False``
    the plain Beer–Lambert law times the two faces' Fresnel losses, (1 − R)² e^{−α d}).
    ``nk`` (..., N) on ``wavelength_nm`` (N,); ``thickness_nm`` broadcasts against the
    leading axes (e.g. shape (M, 1) for M thicknesses).
    """
    N = check_nk(nk, "nk")
    w = as_wavelength_nm(wavelength_nm)
    d = check_positive(thickness_nm, "thickness_nm")
    R = np.abs((N - 1) / (N + 1)) ** 2
    att = np.exp(-4 * np.pi * N.imag / w * d)
    T = (1 - R) ** 2 * att
    if multiple_reflections:
        T = T / (1 - R**2 * att**2)
    return T
