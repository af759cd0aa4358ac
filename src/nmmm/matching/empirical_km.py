"""The industry's empirical calibration: two-constant Kubelka–Munk per unit concentration.

What Datacolor Match Pigment and X-Rite Color iMatch do with a dilution ladder, on the same ladder
files as the physical calibration (:mod:`nmmm.matching.calibration`), so both can be compared.

- :func:`duncan_mixing` — Duncan's rule: K_mix = Σ c_i K_i, S_mix = Σ c_i S_i (c_i the volume
  fractions, K_i and S_i per unit fraction).
- :func:`empirical_reflectance` — the measured reflectance of a film: Kubelka's hyperbolic
  solution for thickness X over a substrate R_g (:func:`nmmm.layers.km_reflectance`), then
  Saunderson's surface correction R = k1 + (1 − k1)(1 − k2) R_b / (1 − k2 R_b), the k1 term
  dropped when the specular component is excluded (de:8, 0:45a, 45a:0); at 0:45a / 45a:0 the
  diffuse flux leaves towards the 45° viewer through the surface, (1 − k2) → (1 − R_F(45°))/n²
  (``exit_factor``; the same forms as :func:`nmmm.layers.geometries.geometry_reflectance`).
- :func:`fit_km_constants` — K_i(λ), S_i(λ) per unit concentration fitted wavelength by
  wavelength (least squares on ln K, ln S) to measured films of known concentrations, thicknesses
  and substrates.
- :func:`calibrate_empirical` — the same from a ladder of recipes (:class:`LadderSample`): the
  concentrations, thicknesses, substrates and binder index read from each recipe; ΔE00 of the fitted
  and the left-out samples. Returns an :class:`EmpiricalCalibration`.

Saunderson constants: k1 = ((n − 1)/(n + 1))², the Fresnel reflectance of the binder at normal
incidence (:func:`nmmm.layers.saunderson_k1`), and k2 the binder surface's internal reflectance for
diffuse light, k2 = 1 − (1 − r_e)/n² (:func:`nmmm.layers.saunderson_k2`; Judd 1942: 0.596 at
n = 1.5), both at the binder's index at each wavelength — in place of the 0.04 and 0.6 often fixed
in practice (they are what those numbers approximate at n = 1.5).

Units: K and S per µm per unit volume fraction; thickness in µm.

Identifiability: 2 unknowns per colourant per wavelength. Opaque films fix only K/S ratios (the
overall scale of K and S then comes from films that do not hide: thin, or over black and white);
fewer fitted samples than unknowns is an error.

References
----------
- D. R. Duncan, "The colour of pigment mixtures", Proc. Phys. Soc. 52, 390 (1940).
  doi:10.1088/0959-5309/52/3/310
- P. Kubelka, "New contributions to the optics of intensely light-scattering materials. Part I",
  J. Opt. Soc. Am. 38, 448 (1948). doi:10.1364/JOSA.38.000448
- J. L. Saunderson, "Calculation of the color of pigmented plastics", J. Opt. Soc. Am. 32, 727
  (1942). doi:10.1364/JOSA.32.000727
- D. B. Judd, "Fresnel reflection of diffusely incident light", J. Res. Natl. Bur. Stand. 29, 329
  (1942).
- E. Allen, "Basic equations used in computer color matching, II. Tristimulus match, two-constant
  theory", J. Opt. Soc. Am. 64, 991 (1974).
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError

__all__ = ["EmpiricalCalibration", "duncan_mixing", "empirical_reflectance", "fit_km_constants", "calibrate_empirical"]

_LN_BOUNDS = (-16.0, 8.0)  # ln of K, S per µm per unit fraction


def duncan_mixing(concentrations, K, S) -> tuple[np.ndarray, np.ndarray]:
    """(K_mix, S_mix) = (Σ c_i K_i, Σ c_i S_i): ``concentrations`` (..., m), ``K``, ``S`` (m, n_λ).

    Examples
    --------
    >>> Km, Sm = duncan_mixing([0.1, 0.3], [[2.0], [0.0]], [[1.0], [10.0]])
    >>> float(Km[0]), float(Sm[0])
    (0.2, 3.1)
    """
    c = np.asarray(concentrations, float)
    return c @ np.asarray(K, float), c @ np.asarray(S, float)


def empirical_reflectance(K_mix, S_mix, thickness_um, substrate_reflectance, k1, k2, specular: str = "excluded",
                          exit_factor=None) -> np.ndarray:
    """Measured reflectance of a KM film of ``K_mix``, ``S_mix`` (per µm) and ``thickness_um`` over
    a substrate, with Saunderson's correction (module docstring); everything broadcasts.
    ``exit_factor``: what of the internal diffuse flux reaches the instrument, 1 − k2 (sphere
    geometries, the default) or (1 − R_F(45°))/n² (0:45a, 45a:0)."""
    from nmmm.layers.kubelka_munk import km_reflectance, saunderson

    Rb = km_reflectance(np.maximum(K_mix, 0.0), np.maximum(S_mix, 0.0), thickness_um, substrate_reflectance)
    if exit_factor is None:
        return saunderson(Rb, k1, k2, specular=specular)
    body = (1 - np.asarray(k1, float)) * np.asarray(exit_factor, float) * Rb / (1 - np.asarray(k2, float) * Rb)
    return body + k1 if specular == "included" else body


def _inverse_saunderson(R, k1, k2, specular, exit_factor=None):
    """R_b from a measured R (Saunderson's relation solved for R_b)."""
    r = R - k1 if specular == "included" else R
    a = (1 - k1) * ((1 - k2) if exit_factor is None else exit_factor)
    return np.clip(r / (a + k2 * r), 1e-4, 0.9999)


def _start(c, q, X, Rg, R, k1, k2, specular, exit_factor=None):
    """A start for one wavelength: K/S of each film from R∞ (opaque approximation), the homogeneous
    Duncan system Σ c_i K_i − q Σ c_i S_i = 0 solved for the ratios (smallest singular vector), the
    common scale by a 1-D search on the full model."""
    A = np.concatenate([c, -q[:, None] * c], axis=1)
    v = np.linalg.svd(A)[2][-1]
    v = np.abs(v) if v.sum() >= 0 else np.abs(-v)
    v = np.maximum(v, 1e-6 * max(v.max(), 1e-12))
    m = c.shape[1]
    best = None
    for scale in np.geomspace(1e-3, 1e3, 13):
        K, S = v[:m] * scale, v[m:] * scale
        r = empirical_reflectance(c @ K, c @ S, X, Rg, k1, k2, specular, exit_factor) - R
        e = float(r @ r)
        if best is None or e < best[0]:
            best = (e, np.log(np.concatenate([K, S])))
    return np.clip(best[1], *_LN_BOUNDS)


def fit_km_constants(concentrations, thickness_um, substrate_reflectance, reflectance, k1, k2,
                     specular: str = "excluded", exit_factor=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """K and S (each (m, n_λ), per µm per unit fraction) of m colourants from n films.

    ``concentrations`` (n, m) volume fractions; ``thickness_um`` (n,); ``substrate_reflectance``
    (n,) or (n, n_λ); ``reflectance`` (n, n_λ) measured; ``k1``, ``k2`` (and ``exit_factor``,
    :func:`empirical_reflectance`) (n_λ,) or scalars. Each
    wavelength is a least-squares fit of ln K_i, ln S_i (trf, bounded), started from the opaque
    Duncan solution and from the previous wavelength's solution, the better kept. Returns
    ``(K, S, rms)`` with ``rms`` the residual RMS per wavelength.

    Examples
    --------
    Two films of one colourant (a thin one and a thick one) fix its K and S:

    >>> from nmmm.matching.empirical_km import empirical_reflectance as er
    >>> c, X, Rg = np.array([[0.1], [0.1]]), np.array([5.0, 50.0]), np.array([0.0, 0.0])
    >>> R = er(0.1 * 0.5, 0.1 * 4.0, X, Rg, 0.04, 0.6)[:, None]
    >>> K, S, rms = fit_km_constants(c, X, Rg, R, 0.04, 0.6)
    >>> [round(float(K[0, 0]), 4), round(float(S[0, 0]), 4)]
    [0.5, 4.0]
    """
    from scipy.optimize import least_squares

    c = np.asarray(concentrations, float)
    R = np.asarray(reflectance, float)
    if c.ndim != 2 or R.ndim != 2 or c.shape[0] != R.shape[0]:
        raise InvalidInputError(f"concentrations (n, m) and reflectance (n, n_wavelengths) must share n; got {c.shape}, {R.shape}")
    n, m = c.shape
    nw = R.shape[1]
    if n < 2 * m:
        raise InvalidInputError(f"{2 * m} unknowns per wavelength (K and S of {m} colourant(s)) from {n} fitted film(s): more "
                                f"unknowns than data — measure at least {2 * m} films (e.g. masstone, tints with white, "
                                "over black) or calibrate fewer colourants")
    if np.any(c.sum(axis=0) <= 0):
        raise InvalidInputError("a colourant has concentration 0 in every fitted film: its K and S cannot be fitted")
    X = np.broadcast_to(np.asarray(thickness_um, float), (n,))
    Rg = np.broadcast_to(np.asarray(substrate_reflectance, float).reshape(n, -1), (n, nw))
    k1 = np.broadcast_to(np.asarray(k1, float), (nw,))
    k2 = np.broadcast_to(np.asarray(k2, float), (nw,))
    ex = None if exit_factor is None else np.broadcast_to(np.asarray(exit_factor, float), (nw,))
    K, S, rms = np.zeros((m, nw)), np.zeros((m, nw)), np.zeros(nw)
    prev = None
    for j in range(nw):
        ej = None if ex is None else ex[j]
        Rb = _inverse_saunderson(R[:, j], k1[j], k2[j], specular, ej)
        q = (1 - Rb) ** 2 / (2 * Rb)

        def res(z, j=j, ej=ej):
            e = np.exp(z)
            return empirical_reflectance(c @ e[:m], c @ e[m:], X, Rg[:, j], k1[j], k2[j], specular, ej) - R[:, j]

        best = None
        for z0 in [_start(c, q, X, Rg[:, j], R[:, j], k1[j], k2[j], specular, ej)] + ([prev] if prev is not None else []):
            r = least_squares(res, z0, bounds=_LN_BOUNDS, method="trf", xtol=1e-10, ftol=1e-12, gtol=1e-12)
            if best is None or r.cost < best.cost:
                best = r
        prev = best.x
        K[:, j], S[:, j] = np.exp(best.x[:m]), np.exp(best.x[m:])
        rms[j] = float(np.sqrt(np.mean(best.fun**2)))
    return K, S, rms


@dataclass
class EmpiricalCalibration:
    """K and S per unit concentration of each colourant, and how well they reproduce the ladder."""

    colourants: tuple
    wavelength_nm: np.ndarray
    K: np.ndarray  # (m, n_λ) per µm per unit volume fraction
    S: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    specular: str
    de00_after: dict
    left_out: tuple
    predicted: dict = field(default_factory=dict)
    rms: np.ndarray = field(default_factory=lambda: np.zeros(0))
    time_s: float = 0.0
    illuminant: str = "D65"
    exit_factor: np.ndarray | None = None  # (1 − R_F(45°))/n² at 0:45a / 45a:0; None: 1 − k2
    geometry: str = "de:8"
    warnings: list = field(default_factory=list)  # what the ladder fixes poorly (also issued as IdentifiabilityWarning)

    def reflectance(self, concentrations: dict, thickness_um: float, substrate_reflectance) -> np.ndarray:
        """The predicted spectrum of a film of ``concentrations`` (compound → volume fraction)."""
        unknown = [k for k in concentrations if k not in self.colourants]
        if unknown:
            raise InvalidInputError(f"no K, S for {unknown}: this calibration has {list(self.colourants)}")
        c = np.array([concentrations.get(k, 0.0) for k in self.colourants])
        Km, Sm = duncan_mixing(c, self.K, self.S)
        return empirical_reflectance(Km, Sm, thickness_um, substrate_reflectance, self.k1, self.k2, self.specular,
                                     self.exit_factor)

    def table(self) -> list[dict]:
        """One row per wavelength: K and S of each colourant (per µm per unit fraction), k1, k2."""
        rows = []
        for j, w in enumerate(self.wavelength_nm):
            row = {"wavelength_nm": float(w)}
            for i, name in enumerate(self.colourants):
                row[f"K_{name}_per_um"] = float(self.K[i, j])
                row[f"S_{name}_per_um"] = float(self.S[i, j])
            row["k1"], row["k2"] = float(self.k1[j]), float(self.k2[j])
            rows.append(row)
        return rows


_VARIABLE = ("name", "description")  # keys of a ladder sample that the empirical model reads, or ignores


def _film_of(sample):
    """(wavelength, concentrations {compound: fraction}, thickness µm, substrate R, n_binder, geometry, signature, pigments)."""
    from nmmm.recipes.paint_stack import geometry_of
    from nmmm.matching.calibration import _materials
    from nmmm.recipes.run import _grid
    from nmmm.recipes.schema import parse_recipe, read_toml

    raw, _, base = read_toml(sample.recipe)
    base = base if base is not None else sample.base_dir
    rec = parse_recipe(raw, base_dir=base)
    if rec.coats is not None or rec.film is None or not rec.pigments:
        raise InvalidInputError(f"sample {sample.name!r}: the empirical (Kubelka-Munk) mode needs a [film] recipe with "
                                "[[pigments]] (not [[coats]] or a single pigment)")
    w = _grid(rec)
    conc = {}
    for p in rec.pigments:
        conc[p.compound] = conc.get(p.compound, 0.0) + p.fraction
    mats = _materials(raw, rec, w, base)
    nb = np.asarray(mats[rec.binder.compound].nk(w)).real
    g = geometry_of(rec)
    sig = copy.deepcopy({k: v for k, v in raw.items() if k not in _VARIABLE})
    film = dict(sig.get("film", {}))
    film.pop("thickness_nm", None)
    film.pop("substrate_reflectance", None)
    sig["film"] = film
    pigs = {}
    for p in sig.pop("pigments", []):
        q = {k: v for k, v in p.items() if k != "fraction"}
        if p.get("fraction", 0) > 0 or q["compound"] not in pigs:
            pigs[q["compound"]] = q
    return w, conc, rec.film.thickness_nm / 1000.0, rec.film.substrate_reflectance, nb, g, sig, pigs


def _check_same_base(films, names):
    """Ladder samples may differ in pigment fractions, film thickness and substrate only."""
    ref_sig, ref_pigs = films[0][6], dict(films[0][7])
    for f, name in zip(films[1:], names[1:]):
        sig, pigs = f[6], f[7]
        for key in sorted(set(sig) | set(ref_sig)):
            if sig.get(key) != ref_sig.get(key):
                raise InvalidInputError(f"sample {name!r} differs from sample {names[0]!r} in [{key}]: the empirical "
                                        "(Kubelka-Munk) calibration can use samples that differ only in pigment fractions, "
                                        "film thickness_nm and substrate_reflectance (one K, S per colourant)")
        for comp, q in pigs.items():
            if comp in ref_pigs and q != ref_pigs[comp]:
                diff = sorted(k for k in set(q) | set(ref_pigs[comp]) if q.get(k) != ref_pigs[comp].get(k))
                raise InvalidInputError(f"sample {name!r}: pigment {comp!r} differs from the other samples in {diff}; a "
                                        "K, S per unit concentration belongs to one grade (same size and shape) — "
                                        "calibrate the other grade as its own colourant")
            ref_pigs.setdefault(comp, q)
        if not np.array_equal(f[0], films[0][0]):
            raise InvalidInputError(f"sample {name!r}: its wavelength grid differs from sample {names[0]!r}'s")


def _surface_terms(geometry: str, n_binder) -> tuple[str, np.ndarray | None]:
    """(specular, exit_factor) of Saunderson's correction at the recipe's geometry, as
    :func:`nmmm.layers.geometries.geometry_reflectance` has them: di:8 and 0:d include the
    specular component, de:8 excludes it; 0:45a and 45a:0 exclude it and the diffuse flux
    leaves at 45° through the surface, (1 − R_F(45°))/n² in place of 1 − k2."""
    from nmmm.layers.fresnel_equations import fresnel
    from nmmm.layers.geometries import check_geometry

    g = check_geometry(geometry)
    if g in ("di:8", "0:d"):
        return "included", None
    if g == "de:8":
        return "excluded", None
    n = np.asarray(n_binder, float)
    r45 = fresnel(n, 1.0, np.degrees(np.arcsin(np.sin(np.radians(45.0)) / n))).R
    return "excluded", np.asarray((1 - r45) / n**2, float)


def _identifiability(c, X, Rg, R, wavelength_nm, colourants) -> list[str]:
    """What a ladder of fitted films (``c`` (n, m), ``X``, ``Rg``, measured ``R`` (n, n_λ)) fixes poorly,
    each also issued as an IdentifiabilityWarning: as many films as unknowns (the fit can follow every
    measurement, noise included), and wavelengths where no contrast pair — two films of one recipe over
    different substrates or at different thicknesses — differs by more than :data:`CONTRAST` in measured
    reflectance: there K and S are fixed as a ratio far better than in scale (module docstring; in
    tests/matching/test_calibration_empirical.py, up to 50 times off with noise 0.002 where a pair hides,
    within 10 % where it differs by 0.02 or more)."""
    import warnings

    from nmmm.matching.recipe_match import IdentifiabilityWarning

    n, m = c.shape
    notes = []
    if n == 2 * m:
        notes.append(f"{n} fitted films for {2 * m} unknowns per wavelength (K and S of {', '.join(colourants)}): the fit "
                     "can follow every measurement, its noise included, so its ΔE00 on the fitted films checks little "
                     "— measure more films or leave fewer out")
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n) if np.allclose(c[i], c[j], rtol=1e-9, atol=1e-12)
             and (abs(Rg[i] - Rg[j]) > 0.05 or abs(X[i] - X[j]) > 0.1 * X[i])]
    contrast = np.max([np.abs(R[i] - R[j]) for i, j in pairs], axis=0) if pairs else np.zeros(R.shape[1])
    poor = contrast <= CONTRAST
    if poor.any():
        where = ("at every wavelength" if poor.all() else
                 f"at {poor.sum()} of {poor.size} wavelengths ({wavelength_nm[poor].min():g}-{wavelength_nm[poor].max():g} nm)")
        what = ("no two fitted films share a recipe over different substrates or at different thicknesses" if not pairs else
                f"the fitted films of one recipe over different substrates or at different thicknesses differ by at most "
                f"{CONTRAST:g} in reflectance (they hide)")
        notes.append(f"{where}, {what}: K and S are fixed there as a ratio far better than in scale, so the constants "
                     "(km_constants.csv) may be far off for films of another thickness or hiding — add a film that does "
                     "not hide, over black and over white (a contrast pair)")
    for note in notes:
        warnings.warn(note, IdentifiabilityWarning, stacklevel=3)
    return notes


#: a contrast pair fixes the scale of K and S where its two measured reflectances differ by more than this
#: (5 times a spectrophotometer's typical repeatability, 0.002)
CONTRAST = 0.01


def calibrate_empirical(samples, left_out=(), illuminant: str = "D65") -> EmpiricalCalibration:
    """K, S per unit concentration of every colourant of the ladder ``samples`` (LadderSample,
    as for :func:`~nmmm.matching.calibration.calibrate_colourant`), fitted on all but ``left_out``."""
    from nmmm.colour import delta_e2000, spectra_to_lab
    from nmmm.layers.kubelka_munk import saunderson_k1, saunderson_k2

    t0 = time.perf_counter()
    names = [s.name for s in samples]
    missing = [n for n in left_out if n not in names]
    if missing:
        raise InvalidInputError(f"left_out names {missing}, not among the samples {names}")
    films = [_film_of(s) for s in samples]
    _check_same_base(films, names)
    w = films[0][0]
    fitted = [i for i, n in enumerate(names) if n not in left_out]
    colourants = tuple(sorted({k for i in fitted for k, v in films[i][1].items() if v > 0}))
    if not colourants:
        raise InvalidInputError("no fitted sample has a pigment with a fraction > 0")
    extra = sorted({k for f in films for k, v in f[1].items() if v > 0} - set(colourants))
    if extra:
        raise InvalidInputError(f"left-out samples hold {extra}, which no fitted sample has: their K, S would be unknown")
    c = np.array([[f[1].get(k, 0.0) for k in colourants] for f in films])
    X = np.array([f[2] for f in films])
    Rg = np.array([f[3] for f in films], float)
    R = np.stack([np.asarray(s.reflectance, float) for s in samples])
    if R.shape[1] != w.size:
        raise InvalidInputError(f"{R.shape[1]} measured values per sample, the recipes' grid has {w.size}")
    nb = films[0][4]
    k1, k2 = np.asarray(saunderson_k1(nb), float), np.asarray(saunderson_k2(nb), float)
    geometry = films[0][5]
    specular, exit_factor = _surface_terms(geometry, nb)
    K, S, rms = fit_km_constants(c[fitted], X[fitted], Rg[fitted], R[fitted], k1, k2, specular, exit_factor)
    cal = EmpiricalCalibration(colourants, w, K, S, k1, k2, specular, {}, tuple(left_out), rms=rms, illuminant=illuminant,
                               exit_factor=exit_factor, geometry=geometry)
    cal.warnings = _identifiability(c[fitted], X[fitted], Rg[fitted], R[fitted], w, colourants)
    for i, name in enumerate(names):
        pred = cal.reflectance(dict(zip(colourants, c[i])), X[i], Rg[i])
        cal.predicted[name] = pred
        cal.de00_after[name] = float(delta_e2000(spectra_to_lab(w, np.clip(R[i], 0, None), illuminant),
                                                 spectra_to_lab(w, pred, illuminant)))
    cal.time_s = time.perf_counter() - t0
    return cal
