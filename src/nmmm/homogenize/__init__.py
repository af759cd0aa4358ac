"""FFT homogenization: the effective permittivity of a periodic microstructure.

Public API
----------
- :func:`fft_permittivity` — labels + {label: ε} -> :class:`FFTHomogenization`
  (``.tensor``, ``.iterations``, residual histories, local fields on request).
- :func:`fft_permittivity_spectrum` — the same over a spectrum, chunks of wavelengths on a Dask
  cluster (local by default, or a scheduler address), warm starts along each chunk.
- :func:`two_phase_spectrum` — a two-phase cell at every wavelength from one Lanczos run per
  loading (Bergman's spectral representation: the wavelength is only a shift of the system).
- :func:`homogenize` — Microstructure + {phase: Material} -> :class:`HomogenizedMaterial`
  (a :class:`nmmm.materials.material.DerivedMaterial`, possibly anisotropic).
- :func:`extrapolate_resolution`, :func:`richardson` — first-order extrapolation to zero voxel size.
- Green operators: :data:`GREEN_OPERATORS`, :func:`green_operator`.
- Solvers: :data:`SOLVERS` (COCG default; BiCGStab, GMRES fallbacks; Eyre-Milton reference).
- Validity: :func:`check_periodicity`, :func:`periodize_mirror`, :func:`check_quasistatic`,
  :func:`size_parameter`, :class:`QuasiStaticWarning`.
- Reference cells with exact answers: :mod:`nmmm.homogenize.geometries`.
- Worked example: :func:`nmmm.demo.homogenization.demo` (hematite coating at 5/7/10 %).
- CLI: ``nmmm homogenize run CELL --eps 0=2.25 --eps 1=-50+20j``, ``nmmm homogenize demo DIR``.

Method in one paragraph: the Galerkin (projection) form of the periodic Lippmann-Schwinger
equation, Γ ε x = −Γ ε E0, is complex symmetric and solved by COCG without a reference
medium (robust for metals, ε ≈ −50 + 20i next to 2.25); BiCGStab and GMRES are fallbacks,
Eyre-Milton and Moulinec-Suquet are kept as references. Γ is stored as per-axis 1-D symbol
factors (spectral, Willot 2014 finite-difference, Willot 2015 rotated; ``green=None`` picks
the rotated one, or the finite-difference one for 3-D low-loss metal cells, and reports it) and
evaluated on the fly in fused Numba kernels; FFTs are scipy.fft in place with 2 workers,
complex128 or complex64.

Known limitations
-----------------
- Errors are first order in the voxel size for smooth inclusions (2-3 % at 32³ for a
  metal-core coated sphere); :func:`extrapolate_resolution` helps there, not at corner
  singularities. The metal-dielectric checkerboard has no converging answer on any grid.
- The rotated (default) operator connects voxels that touch only at a corner; for
  contact-dominated cells compare with ``green="willot2014"``.
- Near-plasmonic contrasts (ε2/ε1 close to −1, e.g. −3 + i next to 2.25) on cells with
  corners and contacts: the result does not settle as the grid is refined (Keller duality
  off by 2-4 % at 32²-128² with the spectral and rotated operators, 11-24 % with
  ``green="willot2014"``). Dielectric and strongly metallic (−50 + 20i) contrasts are fine.
- Quasi-static only: features must be small against λ/n (a warning says when not).
- No GPU backend yet (design in docs/gpu-backend.md: a CuPy port would replace scipy.fft and
  the four kernels).
- complex64 cannot reach tol 1e-5 on 3-D cells with a low-loss metal (ε ≈ −50 + 1..2i: COCG
  stalls at 1e-5 to 6e-5 with any operator); with ``green=None`` such solves run in complex128
  (reported in ``switches``), where 64³ flakes converge in 432-505 projections and spheres in
  118-304 (benchmarks/bench_fft_metals.py).
- Low-loss metal platelets near their in-plane plasmon resonance (ε_m ≈ ε_h (1 − 1/L), L the
  depolarisation factor; e.g. 2-voxel discs of radius 21 in 2.25 at ε = −50 + 1..5i) are
  near-singular (the count grows as 1/|Im s|, s = ε_h/(ε_m − ε_h)). On 128³, x loading, complex128
  COCG: −50 + 5i does not reach tol 1e-5 in 500 projections with either Willot operator (best
  5.2e-5), −50 + 2i needs 1346 with ``willot2014`` (the Lanczos counts quoted before, 1505 and
  ≈ 3000 at −50 + 1i, overstate COCG's), and at −50 + 1i COCG was stopped after 150 projections
  (maxiter 500) with no decrease of its residual yet — the check now starts at 0.6 × maxiter
  (``fft.PREDICT``: from 150 on it also stopped solves that converge within maxiter); every
  such stop is in ``switches`` and the ConvergenceError gives the maxiter the prediction asks for. At 64³ all twelve metal cases of
  benchmarks/bench_fft_metals.py converge within 500 (flakes at −50 + 1i: 498). Without local
  fields COCG also stops when the estimated error of ε_jj is ≤ tol (``stop="auto"``, COCG's Gauss
  quadrature of bᵀA⁻¹b; reported): 64³ flakes in 242-431, 128³ flakes at −50 + 5i, 2i, 1i in 358,
  816 and 1497 (ε_xx within 7.1e-7 of a residual-1e-9 solve), so at 128³ −50 + 2i and 1i still
  exceed 500. Real aluminium
  in the visible (Im ε ≥ 0.19 |ε|, |Im s| ≥ 0.013) is far from this: 118-216 projections per wavelength (x, y).
- Lanczos (``method="lanczos"``, chosen by ``"auto"`` for two-phase spectra when cheaper) drifts
  from COCG for a low-loss metal in finite precision (64³ flakes at −50 + 1i: 1284 steps against
  COCG's 498, ε_xx 2.3e-3 apart, COCG's true residual 9.7e-6), so ``"auto"`` keeps per-wavelength
  COCG there.
"""

from nmmm.homogenize.fft import FFTHomogenization, fft_permittivity
from nmmm.homogenize.spectral_batches import fft_permittivity_spectrum
from nmmm.homogenize.bergman_lanczos import two_phase_spectrum
from nmmm.homogenize.material import HomogenizedMaterial, apparent_property, homogenize
from nmmm.homogenize.resolution import ResolutionStudy, extrapolate_resolution, richardson
from nmmm.homogenize.green import GREEN_OPERATORS, GreenOperator, green_operator
from nmmm.homogenize.solvers import SOLVERS
from nmmm.homogenize.validity import (
    PeriodicityWarning,
    QuasiStaticWarning,
    check_periodicity,
    check_quasistatic,
    feature_size_nm,
    periodize_mirror,
    size_parameter,
)

__all__ = [
    "fft_permittivity",
    "fft_permittivity_spectrum",
    "two_phase_spectrum",
    "FFTHomogenization",
    "homogenize",
    "HomogenizedMaterial",
    "apparent_property",
    "extrapolate_resolution",
    "richardson",
    "ResolutionStudy",
    "GREEN_OPERATORS",
    "GreenOperator",
    "green_operator",
    "SOLVERS",
    "check_periodicity",
    "check_quasistatic",
    "feature_size_nm",
    "periodize_mirror",
    "size_parameter",
    "QuasiStaticWarning",
    "PeriodicityWarning",
]
