"""An effect coat described by its composition: flakes and pigments in one basecoat.

- :class:`FlakeSpec` — the flakes as made: material (a compound, or a layered flake given as
  an :class:`nmmm.layers.Stack`, e.g. Fe2O3 or TiO2 on mica, alumina or silica), diameter
  distribution, thickness, volume fraction in the basecoat, orientation (the tilt scale of
  the deposit model, or a tabulated density of normals per steradian).
- :class:`EffectCoat` — the coat: flakes, coloured/white pigments in the same binder
  (:class:`nmmm.layers.pigment_mixture.Component`, the ``[[pigments]]`` of films), binder,
  basecoat thickness, clear coat above, primer/substrate below.
  :meth:`EffectCoat.derived` gives the layer parameters the BRDF needs — never typed by hand:
  flake number density, optical depth τ (flake face area per unit area, and its projection
  along the tilt distribution), tilt distribution and depth profile of the flakes;
  :meth:`EffectCoat.brdf` returns ``(PaintBRDF, FlakeList)`` for the multi-angle colour, the
  renderer and the sparkle images (the same flakes, averaged and discrete).
- :meth:`EffectCoat.from_sem` — the flake statistics measured on SEM cross-sections
  (:func:`nmmm.microstructure.estimate_flakes`) as a :class:`FlakeSpec`.

Derivation (``derive=``)
------------------------
``"deposit"`` (default): the flakes of a :func:`nmmm.microstructure.flake_deposit` in a
``cell_nm`` × coat-thickness cell (Couka, Willot & Jeulin 2012). The deposit places every
flake drawn (or refuses a coat it cannot hold, naming the largest fraction that fits: the median
capacity of fixed reference cells of the composition, the same verdict and limit for every seed —
:meth:`EffectCoat.deposit`) and lets flakes fall without rotating them, so the ensemble τ is φ H / t and the area-weighted tilt law
is the drawn half-normal one; both are used as such — one cell's τ (Poisson count of ~300-800
flakes × log-normal areas, ±5 %) and a kernel estimate of its tilts made L*(15°) jump by up to
2.4 between fractions 1 % apart and spread it by ~2 over seeds. The depth profile is the uniform
band with the flake centres' area-weighted mean and variance of depth, averaged over
:data:`BAND_REALISATIONS` deposits (SE ~0.004 of the coat). The cell's own τ, rms tilt (± SE)
and the band's SE are in :attr:`DerivedFlakeLayer.realisation`; the cell's flakes remain the
discrete list (glints, sparkle, plate tiles) and its number density.
``"volume"``: without a deposit — N_A = φ H / (π⟨D²⟩/4 · t) flakes per unit area, τ = φ H / t,
tilts from the deposit model's law (half-normal in θ of scale ``tilt_std_deg``, azimuth
uniform) and flakes uniform through the coat; the discrete list is drawn at random.

Expert override: ``optical_depth`` and ``tilt_deg`` (a Gaussian per steradian of that σ, the
law of :func:`nmmm.appearance.flakes.gaussian_tilt`) replace the derived values when given —
the old ``[effect]`` keys of a recipe.

Errors name the field (``flakes.fraction: ...``); the recipe prefixes them with ``effect.``.

References
----------
- E. Couka, F. Willot, D. Jeulin, "A mixed Boolean and deposit model for the modeling of metal
  pigments in paint layers", Image Anal. Stereol. 32(2) (2012).
- S. Ershov, K. Kolchin, K. Myszkowski, "Rendering pearlescent appearance based on
  paint-composition modelling", Computer Graphics Forum 20(3) (2001) 227.
- F. J. Maile, G. Pfaff, P. Reynders, "Effect pigments — past, present and future",
  Prog. Org. Coat. 54 (2005) 150 (metal-oxide-on-mica, alumina and silica pigments).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.spectra import as_wavelength_nm

__all__ = ["FlakeSpec", "EffectCoat", "DerivedFlakeLayer"]

#: deposits whose depth bands are averaged for the derived flake band (EffectCoat._realisation_stats)
BAND_REALISATIONS = 32

#: reference deposits whose capacities give the largest fraction the deposit model holds (EffectCoat.deposit_limit)
CAPACITY_REALISATIONS = 64

#: deposits tried, from seeds derived from the coat's seed, before a fraction under the limit is given up
DEPOSIT_TRIES = 64

#: spawn key of the retried deposits (the band's realisations use spawn keys (1,) … (31,))
_RETRY_KEY = 18_0018

#: capacities of the deposit model per composition (box, diameters, thickness, tilt): EffectCoat.deposit_limit
_CAPACITY_CACHE: dict = {}

#: thinnest layer of a layered flake that is still a film (about one oxide unit cell)
_MIN_LAYER_NM = 1.0


def _num(v, key, lo=None, hi=None, lo_open=True, what="") -> float:
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{key}: must be a number{what}, got {v!r}") from None
    if not math.isfinite(x):
        raise InvalidInputError(f"{key}: must be finite{what}, got {v!r}")
    if lo is not None and (x <= lo if lo_open else x < lo):
        raise InvalidInputError(f"{key}: must be {'>' if lo_open else '>='} {lo:g}{what}, got {x:g}")
    if hi is not None and x > hi:
        raise InvalidInputError(f"{key}: must be <= {hi:g}{what}, got {x:g}")
    return x


@dataclass(frozen=True)
class FlakeSpec:
    """The flakes of an effect coat, as a formulator describes them.

    material : str, Material, complex or nmmm.layers.Stack
        ``"aluminium"`` (Rakić), ``"mica"`` (TiO2/mica/TiO2, :func:`mica_pigment` defaults), a
        database key / :class:`~nmmm.materials.Material` (a metal: opaque flake; a dielectric:
        a platelet of that thickness), or a layered flake (a :class:`nmmm.layers.Stack` whose
        layers, top to bottom, make the platelet; its ambient/substrate are ignored — the
        flake sits in the binder).
    diameter_um, diameter_std_um : mean and standard deviation of the flake diameters
        (log-normal), µm.
    thickness_nm : flake thickness; for a layered flake None means the sum of its layers.
    fraction : volume fraction of flakes in the basecoat, in [0, 1).
    tilt_std_deg : orientation spread — the scale of the half-normal tilt law of the deposit
        model (:func:`nmmm.microstructure.flake_deposit`), degrees.
    tilt_density : optional ``(tilt_deg, density_per_sr)`` tabulated density of flake normals
        (replaces ``tilt_std_deg``; needs ``derive="volume"``).
    face_roughness : GGX α of the flake faces (microfacets composed with the tilt,
        :meth:`TiltDistribution.roughened`; Walter et al. 2007); 0 = mirror faces (default).
        About 0.05 is a plausible value for milled aluminium flakes (ASSUMED, no measured α is
        cited here; ragged "cornflake" grades higher): it widens the near-specular lobe and lifts
        the far-from-specular flake light, so L* keeps falling beyond 45° aspecular.
    edge_width_nm : width w of the scattering rim round each flake; the rim fraction of the
        light meeting a flake is f_e = 4 w / ⟨D⟩ (:func:`nmmm.appearance.flakes.edge_scatter_fraction`);
        0 = no rims (default). 500 nm is that function's ASSUMED wavelength-scale width.
        Both default to 0 because the plate renderer's discrete glints are still mirror flakes
        without rims (nmmm.appearance.render.plate): with them on, the glints of the shipped red
        metallic are 1.5x its statistical flake term at 450 nm (review O, session 4).
    """

    material: object = "aluminium"
    diameter_um: float = 20.0
    diameter_std_um: float = 6.0
    thickness_nm: float | None = 300.0
    fraction: float = 0.008
    tilt_std_deg: float = 6.0
    tilt_density: tuple | None = None
    name: str = ""
    face_roughness: float = 0.0
    edge_width_nm: float = 0.0

    def __post_init__(self):
        _num(self.diameter_um, "flakes.diameter_um", 0.0, what=" (flake diameter, µm)")
        _num(self.diameter_std_um, "flakes.diameter_std_um", 0.0, lo_open=False)
        if self.thickness_nm is not None:
            _num(self.thickness_nm, "flakes.thickness_nm", 0.0, what=" (flake thickness, nm)")
        f = _num(self.fraction, "flakes.fraction", 0.0, 1.0, lo_open=False, what=" (a volume fraction: 1 % is 0.01)")
        if f >= 1.0:
            raise InvalidInputError(f"flakes.fraction: must be < 1 (a volume fraction of the coat), got {f:g}")
        _num(self.tilt_std_deg, "flakes.tilt_std_deg", 0.0, 90.0, lo_open=False, what=" (degrees)")
        _num(self.face_roughness, "flakes.face_roughness", 0.0, 1.0, lo_open=False,
             what=" (GGX alpha of the flake faces, 0 = mirror)")
        _num(self.edge_width_nm, "flakes.edge_width_nm", 0.0, lo_open=False, what=" (rim width, nm)")
        if self.tilt_density is not None:
            self.tilt_distribution()  # refuses a table that is not a density, naming the key
        if self.layered:
            self._check_layers()
            total = sum(float(la.thickness_nm) for la in self.material.layers)
            if self.thickness_nm is None:
                object.__setattr__(self, "thickness_nm", total)
            elif not math.isclose(float(self.thickness_nm), total, rel_tol=1e-6):
                raise InvalidInputError(
                    f"flakes.thickness_nm: {float(self.thickness_nm):g} nm, but the layers of the flake add up to "
                    f"{total:g} nm; leave thickness_nm out for a layered flake (it is their sum)")
        elif self.thickness_nm is None:
            raise InvalidInputError("flakes.thickness_nm: required for a flake that is not layered (nm)")

    @property
    def layered(self) -> bool:
        from nmmm.layers import Stack

        return isinstance(self.material, Stack)

    def _check_layers(self, wavelength_nm=None):
        w = np.arange(380.0, 781.0, 20.0) if wavelength_nm is None else as_wavelength_nm(wavelength_nm)
        layers = self.material.layers
        if not layers:
            raise InvalidInputError("flakes.layers: a layered flake needs at least one layer")
        for i, la in enumerate(layers):
            d = np.asarray(la.thickness_nm, float)
            if d.ndim or not (np.isfinite(d) and d >= _MIN_LAYER_NM):
                raise InvalidInputError(
                    f"flakes.layers[{i}].thickness_nm: {d.tolist()!r} nm is not a physical film; a layer of a flake is one "
                    f"thickness >= {_MIN_LAYER_NM:g} nm (about one oxide unit cell)")
            try:
                nk = np.broadcast_to(np.asarray(_nk(la.material, w), complex), w.shape)
            except InvalidInputError as exc:
                raise InvalidInputError(f"flakes.layers[{i}].material: {exc}") from None
            if np.any(~np.isfinite(nk)) or np.any(nk.imag < 0) or np.any(nk.real <= 0):
                bad = nk[~np.isfinite(nk) | (nk.imag < 0) | (nk.real <= 0)][0]
                raise InvalidInputError(
                    f"flakes.layers[{i}].material: n + ik = {bad:.4g} is not a passive medium (needs n > 0 and "
                    "k >= 0 over the grid)")

    def tilt_distribution(self):
        """The analytic tilt distribution of the flakes (before any deposit): the tabulated
        density if given, else the deposit model's half-normal law p(θ) ∝ exp(−θ²/2s²) per
        unit θ, i.e. exp(−θ²/2s²) / (2π sin θ) per steradian."""
        from nmmm.appearance.flakes import TiltDistribution

        if self.tilt_density is not None:
            try:
                t, d = self.tilt_density
                return TiltDistribution.tabulated(t, d, name="tabulated")
            except InvalidInputError as exc:
                raise InvalidInputError(f"flakes.tilt_density: {exc}") from None
            except (TypeError, ValueError):
                raise InvalidInputError("flakes.tilt_density: give (tilt_deg, density_per_sr), two lists of equal "
                                        "length") from None
        s = float(self.tilt_std_deg)
        if s <= 0:
            raise InvalidInputError("flakes.tilt_std_deg: 0 is a Dirac (perfectly flat flakes), not a density; "
                                    "give a spread > 0 degrees")
        t = np.linspace(0.0, 90.0, 8193)
        sin = np.sin(np.radians(np.maximum(t, t[1])))
        dens = np.exp(-0.5 * (t / s) ** 2) / sin * (t <= 80.0)  # the deposit model truncates at 80°
        return TiltDistribution(t, dens, name=f"half-normal tilt s={s:g} deg (deposit law)")

    def optics(self):
        """Flake optics: :class:`MetalFlakeOptics` or :class:`ThinFilmFlakeOptics`."""
        from nmmm.appearance.flakes import MetalFlakeOptics, ThinFilmFlakeOptics, aluminium_flakes, mica_pigment

        m = self.material
        if self.layered:
            layers = tuple((la.material, float(la.thickness_nm), bool(la.coherent)) for la in m.layers)
            return ThinFilmFlakeOptics(layers, name=self.name or "layered flake")
        if isinstance(m, str) and m.lower() in ("aluminium", "aluminum", "al"):
            return aluminium_flakes()
        if isinstance(m, str) and m.lower() == "mica":
            return mica_pigment()
        nk = np.asarray(_nk(m, np.array([550.0])), complex)
        if nk.imag.max() > 1.0:  # a metal: opaque at these thicknesses
            return MetalFlakeOptics(_material(m), name=self.name or f"metal flake ({m})")
        coherent = float(self.thickness_nm) < 1000.0
        return ThinFilmFlakeOptics(((_material(m), float(self.thickness_nm), coherent),),
                                   name=self.name or f"platelet ({m})")

    def diameter_distribution(self):
        mean, std = float(self.diameter_um) * 1e3, float(self.diameter_std_um) * 1e3
        return ("lognormal", mean, std) if std > 0 else mean

    def mean_square_diameter_nm2(self) -> float:
        mean, std = float(self.diameter_um) * 1e3, float(self.diameter_std_um) * 1e3
        return mean * mean + std * std


def _material(m):
    from nmmm.materials import as_material, get

    if isinstance(m, str):
        try:
            return get(m)
        except Exception as exc:  # unknown key: say which
            raise InvalidInputError(f"flakes.material: {m!r} is not a known compound key ({exc})") from None
    return as_material(m)


def _nk(m, w):
    if isinstance(m, (int, float, complex)):
        return np.full(np.shape(w), complex(m))
    if hasattr(m, "nk"):
        return m.nk(w)
    return _material(m).nk(w)


@dataclass(frozen=True)
class DerivedFlakeLayer:
    """Flake-layer parameters derived from the composition (the numbers the BRDF uses)."""

    number_density_per_mm2: float
    optical_depth: float  # flake face area per unit area of paint
    projected_optical_depth: float  # τ·⟨cos θ⟩: the area the flakes cover seen along the normal
    tilt: object  # TiltDistribution
    mean_tilt_deg: float
    depth_range: tuple  # (top, bottom) of the flake band, fractions of the basecoat thickness
    volume_fraction: float
    n_flakes_in_cell: int
    source: str
    overridden: tuple = ()
    #: the deposit cell's own statistics with standard errors (τ, rms tilt, band top), against the
    #: ensemble values used above: ``optical_depth_cell ± optical_depth_cell_se`` etc.
    realisation: dict = field(default_factory=dict)

    def table(self) -> list[dict]:
        """Rows (quantity, value, unit) for reports."""
        return [
            dict(quantity="flakes per mm² (the cell's)", value=self.number_density_per_mm2, unit="1/mm²"),
            dict(quantity="optical depth τ (face area / area)", value=self.optical_depth, unit="1"),
            dict(quantity="projected optical depth τ⟨cos θ⟩", value=self.projected_optical_depth, unit="1"),
            dict(quantity="mean tilt", value=self.mean_tilt_deg, unit="deg"),
            dict(quantity="flake band top (fraction of coat)", value=self.depth_range[0], unit="1"),
            dict(quantity="flake band bottom (fraction of coat)", value=self.depth_range[1], unit="1"),
            dict(quantity="flake volume fraction", value=self.volume_fraction, unit="1"),
        ] + self._realisation_rows()

    def _realisation_rows(self) -> list[dict]:
        r = self.realisation
        if "optical_depth_cell" not in r:
            return []
        return [
            dict(quantity="deposit cell: optical depth τ ± SE", value=r["optical_depth_cell"],
                 unit=f"± {r['optical_depth_cell_se']:.2g}"),
            dict(quantity="deposit cell: rms tilt ± SE (law)", value=r["tilt_rms_deg_cell"],
                 unit=f"± {r['tilt_rms_deg_cell_se']:.2g} deg ({r['tilt_rms_deg_law']:.3g})"),
            dict(quantity="flake band top, SE", value=r["band_top_se"], unit="1"),
        ]


@dataclass(frozen=True, repr=False)
class EffectCoat:
    """A basecoat of flakes and pigments in a binder, under a clear coat, over a primer.

    flakes : FlakeSpec
    pigments : sequence of :class:`nmmm.layers.pigment_mixture.Component` (fractions of the
        dry basecoat), coloured or white pigments between the flakes.
    binder : index or Material of the binder (also the clear coat's).
    coat_thickness_nm : basecoat thickness H (the flakes are inside it).
    clear_coat_nm : clear coat thickness above the basecoat (shifts the flakes' depths).
    roughness : GGX roughness of the clear coat's top surface.
    substrate_reflectance : internal diffuse reflectance of the primer/substrate below (scalar,
        or ``(wavelength_nm, values)``).
    derive : "deposit" or "volume" (module docstring); cell_nm, seed: the deposit's cell and seed.
    optical_depth, tilt_deg : expert override of the derived τ and tilt (Gaussian σ per sr).
    """

    flakes: FlakeSpec = field(default_factory=FlakeSpec)
    pigments: tuple = ()
    binder: object = 1.5
    coat_thickness_nm: float = 20e3
    clear_coat_nm: float = 30e3
    roughness: float = 0.0
    substrate_reflectance: object = 0.35
    derive: str = "deposit"
    cell_nm: tuple = (450e3, 450e3)
    seed: int = 1
    optical_depth: float | None = None
    tilt_deg: float | None = None
    name: str = "effect coat"
    _memo: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        if not isinstance(self.flakes, FlakeSpec):
            raise InvalidInputError("flakes: must be a FlakeSpec")
        object.__setattr__(self, "pigments", tuple(self.pigments))
        H = _num(self.coat_thickness_nm, "coat_thickness_nm", 0.0, what=" (basecoat thickness, nm)")
        _num(self.clear_coat_nm, "clear_coat_nm", 0.0, lo_open=False)
        if self.derive not in ("deposit", "volume"):
            raise InvalidInputError(f"derive: must be 'deposit' or 'volume', got {self.derive!r}")
        fl = self.flakes
        t = float(fl.thickness_nm)
        if t >= H:
            raise InvalidInputError(
                f"flakes.thickness_nm: flakes {t:g} nm thick do not fit in a basecoat {H:g} nm thick; thin the "
                "flakes or thicken the coat (coat_thickness)")
        if fl.tilt_density is not None and self.derive == "deposit":
            raise InvalidInputError("flakes.tilt_density: a tabulated tilt density cannot drive the deposit model "
                                    "(it draws half-normal tilts of scale tilt_std_deg); use derive = 'volume'")
        self._check_packing()
        if self.optical_depth is not None:
            _num(self.optical_depth, "optical_depth", 0.0, lo_open=False)
        if self.tilt_deg is not None:
            _num(self.tilt_deg, "tilt_deg", 0.0, 90.0)
        pvc = sum(float(c.fraction) for c in self.pigments) + float(fl.fraction)
        if pvc >= 1.0:
            raise InvalidInputError(f"pigments: pigments and flakes fill {pvc:g} of the coat (>= 1); the fractions "
                                    "are of the dry basecoat")

    def _check_packing(self):
        """A layer of flakes tilted by θ stacks at least t cos θ + D sin θ high per flake
        (a flake's vertical extent), so the densest fraction the coat can hold is
        φ_max = t / ⟨t cos θ + D sin θ⟩ over the tilt law (and never above 1).

        A cheap check at construction for both derivations; the rigid deposit holds far less (its
        surface is rough: 0.019 against 0.153 for the grey metallic's flakes), and ``derive="deposit"``
        refuses above its own limit (:meth:`deposit_limit`) when the deposit is drawn."""
        fl = self.flakes
        tilt = fl.tilt_distribution()
        th = np.radians(tilt.tilt_deg)
        w = tilt.density * 2 * np.pi * np.sin(th)
        w = w / np.trapezoid(w, th)
        t, D = float(fl.thickness_nm), float(fl.diameter_um) * 1e3
        mean_h = float(np.trapezoid(w * (t * np.cos(th) + D * np.sin(th)), th))
        phi_max = min(1.0, t / mean_h)
        if fl.fraction > phi_max:
            raise InvalidInputError(
                f"flakes.fraction: {fl.fraction:g} of {D / 1e3:g} µm × {t:g} nm flakes cannot fit the coat at a tilt "
                f"spread of {fl.tilt_std_deg:g}° (mean vertical extent {mean_h:.4g} nm per flake): at most "
                f"{phi_max:.3g}; lower the fraction or the tilt spread")

    # -- derivation --------------------------------------------------------------------
    def _box(self):
        return (float(self.cell_nm[0]), float(self.cell_nm[1]), float(self.coat_thickness_nm))

    def _draw_deposit(self, seed):
        from nmmm.microstructure import flake_deposit

        fl = self.flakes
        return flake_deposit(box_nm=self._box(), diameter_nm=fl.diameter_distribution(),
                             thickness_nm=float(fl.thickness_nm), fraction=float(fl.fraction),
                             tilt_std_deg=float(fl.tilt_std_deg), seed=seed)

    def deposit_capacities(self) -> np.ndarray:
        """Capacities (volume fractions, sorted) of :data:`CAPACITY_REALISATIONS` reference cells of the
        deposit model for these flakes, tilt spread, coat and cell
        (:func:`nmmm.microstructure.flakes.flake_deposit_capacity`, fixed reference seeds); computed
        once per composition (~0.2 s) and cached — the fraction and the coat's seed play no part."""
        from nmmm.microstructure.flakes import flake_deposit_capacity

        fl = self.flakes
        key = (self._box(), float(fl.diameter_um), float(fl.diameter_std_um), float(fl.thickness_nm),
               float(fl.tilt_std_deg))
        if key not in _CAPACITY_CACHE:
            caps = flake_deposit_capacity(box_nm=key[0], diameter_nm=fl.diameter_distribution(),
                                          thickness_nm=key[3], tilt_std_deg=key[4],
                                          realisations=CAPACITY_REALISATIONS)
            caps.flags.writeable = False
            _CAPACITY_CACHE[key] = caps
        return _CAPACITY_CACHE[key]

    def deposit_limit(self) -> float:
        """The largest flake fraction the deposit model holds in this coat: the median capacity of
        :meth:`deposit_capacities` (the fraction at which half of the model's cells of this size
        hold all their flakes), rounded down to 3 significant digits — the value the error names."""
        med = float(np.median(self.deposit_capacities()))
        if not med > 0:
            return 0.0
        q = 10.0 ** (math.floor(math.log10(med)) - 2)
        return float(f"{math.floor(med / q + 1e-9) * q:.3g}")

    def deposit(self):
        """The flake deposit of the basecoat (:func:`nmmm.microstructure.flake_deposit`), cached.

        Whether a fraction fits does not depend on the seed. A rigid deposit overflows where its
        roughest tower reaches the top of the coat, so one cell's capacity is broad (pearl of the
        shipped recipe: ~0.015-0.035) and a fraction near a full coat used to be accepted or refused
        by the seed (grey metallic at its 0.008: seed 2 refused; pearl at 0.02: ~1 seed in 4). The rule:

        - above :meth:`deposit_limit` (the median capacity of fixed reference cells of this
          composition) the fraction is refused — ``flakes.fraction``, the value given and the limit;
        - at or below it the deposit of ``seed`` is drawn; if that cell overflows, deposits from seeds
          derived from it (``SeedSequence(seed, spawn_key=(_RETRY_KEY, j))``, j = 1 …
          :data:`DEPOSIT_TRIES` − 1) are tried in turn and the first that holds every flake is the
          cell. Each holds them with probability >= ~1/2 at the limit, so all fail about once in 2⁶⁴.

        A seed whose own deposit fits keeps it (the cell is unchanged); the ensemble values of
        :meth:`derived` do not depend on the cell at all."""
        if "deposit" not in self._memo:
            fl = self.flakes
            phi = float(fl.fraction)
            limit = self.deposit_limit()
            if phi > limit:
                raise InvalidInputError(self._overflow_message(phi, limit))
            last = None
            for j in range(DEPOSIT_TRIES):
                seed = self.seed if j == 0 else np.random.SeedSequence(
                    None if self.seed is None else int(self.seed), spawn_key=(_RETRY_KEY, j))
                try:
                    dep = self._draw_deposit(seed)
                    break
                except InvalidInputError as exc:
                    if not hasattr(exc, "n_fit"):  # not an overflow: the same on every try
                        raise InvalidInputError(f"flakes.fraction: the deposit model cannot place these flakes in the "
                                                f"coat: {phi:g} given; {exc}") from None
                    last = exc
            else:
                raise InvalidInputError(self._overflow_message(phi, limit) + f"; none of {DEPOSIT_TRIES} deposits of "
                                        f"this fraction held all its flakes ({last})")
            self._memo["deposit"] = dep
        return self._memo["deposit"]

    def _overflow_message(self, phi, limit):
        fl = self.flakes
        cell = "×".join(f"{float(c) / 1e3:g}" for c in self.cell_nm)
        return (f"flakes.fraction: the deposit model cannot place these flakes in the coat: {phi:g} given, at most "
                f"{limit:.3g} of these {float(fl.diameter_um):g} µm × {float(fl.thickness_nm):g} nm flakes fit this "
                f"{self.coat_thickness_nm / 1e3:g} µm coat at a tilt spread of {float(fl.tilt_std_deg):g}° (the "
                f"fraction at which half of the model's {cell} µm cells hold all their flakes); lower the fraction or "
                "the tilt spread, or thicken the coat")

    def flake_list(self):
        """The discrete flakes (:class:`nmmm.appearance.flakes.FlakeList`) of one cell: the
        deposit's, or drawn at random for ``derive="volume"``; depths from the coat's top."""
        if "list" not in self._memo:
            from nmmm.appearance.flakes import FlakeList

            fl, n_b = self.flakes, self.n_binder()
            if self.derive == "deposit":
                lst = FlakeList.from_deposit(self.deposit(), fl.optics(), n_binder=n_b,
                                             coat_thickness_nm=float(self.clear_coat_nm))
            else:
                d = self._volume_numbers()
                area = float(self.cell_nm[0]) * float(self.cell_nm[1])
                n = int(np.random.default_rng(self.seed).poisson(d[0] * area))
                c0 = float(self.clear_coat_nm)
                mean = float(fl.diameter_um) * 1e3
                lst = FlakeList.random(fl.optics(), fl.tilt_distribution(), n, region_nm=tuple(self.cell_nm),
                                       mean_diameter_nm=mean, diameter_cv=float(fl.diameter_std_um) * 1e3 / mean,
                                       depth_range_nm=(c0, c0 + float(self.coat_thickness_nm)), n_binder=n_b,
                                       rng=self.seed)
            self._memo["list"] = lst
        return self._memo["list"]

    def _volume_numbers(self):
        fl = self.flakes
        H, t = float(self.coat_thickness_nm), float(fl.thickness_nm)
        na = float(fl.fraction) * H / (math.pi / 4 * fl.mean_square_diameter_nm2() * t)  # per nm²
        return na, float(fl.fraction) * H / t

    def _band(self, dep):
        """(top, bottom) of the uniform band (fractions of the coat) with the area-weighted mean and
        variance of the flake centres' depths, widened by the median flake half height: mean ± √3 sd."""
        H = float(self.coat_thickness_nm)
        a = dep.diameters_nm ** 2
        w = a / a.sum()
        z = dep.depth_nm
        mz = float(np.sum(w * z))
        sz = float(np.sqrt(np.sum(w * (z - mz) ** 2)))
        hh = float(np.median(dep.half_height_nm))
        return max(0.0, mz - math.sqrt(3.0) * sz - hh) / H, min(H, mz + math.sqrt(3.0) * sz + hh) / H

    def _realisation_stats(self, dep, tau, tilt):
        """Depth band of the flakes, averaged over :data:`BAND_REALISATIONS` deposits (this cell's and
        more drawn from ``SeedSequence(seed, spawn_key=(k,))``, ~2 ms each), and this cell's own
        statistics with their standard errors, against the ensemble values the BRDF uses.

        The band is uniform (what the BRDF assumes, nmmm.appearance.brdf.coat_medium) with the flakes'
        mean and variance of depth (:meth:`_band`). One cell's band top moves by ~0.02 of the coat from
        seed to seed (its Poisson count raises or lowers the fill; the 1 %/99 % quantiles used before moved it
        by 0.04), ~0.4 L*(15°) for the red metallic, whose pigment lies above the flakes; the mean of 32 has
        an SE ~0.004. Realisations the deposit refuses (a coat near full) are left out and counted."""
        n = len(dep)
        if n < 2:
            return 0.0, 1.0, {"n_flakes_in_cell": n}
        bands, refused = [self._band(dep)], 0
        for k in range(1, BAND_REALISATIONS):
            try:
                ss = np.random.SeedSequence(None if self.seed is None else int(self.seed), spawn_key=(k,))
                d_k = self._draw_deposit(ss)
            except InvalidInputError:
                refused += 1
                continue
            if len(d_k) >= 2:
                bands.append(self._band(d_k))
        bands = np.array(bands)
        top, bot = (float(v) for v in bands.mean(axis=0))
        se_top = float(bands[:, 0].std(ddof=1) / math.sqrt(len(bands))) if len(bands) > 1 else float("nan")
        a = np.pi / 4 * dep.diameters_nm ** 2
        w = a / a.sum()
        n_eff = 1.0 / float(np.sum(w * w))
        cell = float(self.cell_nm[0]) * float(self.cell_nm[1])
        th = np.arccos(np.clip(dep.normals[:, 2], -1.0, 1.0))
        m2 = float(np.sum(w * th * th))
        m4 = float(np.sum(w * th ** 4))
        rms_se = math.degrees(math.sqrt(max(m4 - m2 * m2, 0.0) / n_eff) / (2.0 * math.sqrt(m2))) if m2 > 0 else 0.0
        tg = np.radians(tilt.tilt_deg)
        pw = tilt.density * np.sin(tg)
        rms_law = math.degrees(math.sqrt(float(np.trapezoid(pw * tg * tg, tg) / np.trapezoid(pw, tg))))
        stats = {"n_flakes_in_cell": n,
                 "optical_depth_cell": float(a.sum() / cell),
                 "optical_depth_cell_se": float(math.sqrt(np.sum(a * a)) / cell),  # compound Poisson: var Σa = λE[a²]
                 "optical_depth_ensemble": float(tau),
                 "tilt_rms_deg_cell": math.degrees(math.sqrt(m2)), "tilt_rms_deg_cell_se": rms_se,
                 "tilt_rms_deg_law": rms_law,
                 "band_top_se": se_top, "band_realisations": int(len(bands)), "band_realisations_refused": int(refused)}
        return top, bot, stats

    def derived(self) -> DerivedFlakeLayer:
        """Flake number density, τ, projected τ, tilt distribution and depth profile."""
        if "derived" in self._memo:
            return self._memo["derived"]
        from nmmm.appearance.flakes import gaussian_tilt

        fl = self.flakes
        if self.derive == "deposit":
            dep = self.deposit()
            # The colour is a property of the composition, not of one 450 µm cell: τ and the tilt law are the
            # ensemble values, which the deposit model gives exactly (it places every flake drawn, or refuses,
            # and lets flakes fall without rotating them, so a realisation's area-weighted tilts are a sample
            # of the drawn half-normal law). One cell's τ (~700 flakes, Poisson count × log-normal areas) and a
            # kernel estimate of its tilts scattered L*(15°) by ~2 (pearl, seeds 1-12); see _realisation_stats.
            tau = self._volume_numbers()[1]
            na = dep.number_density_per_nm2  # the cell's flakes: the discrete list, the plate's tiles
            tilt = fl.tilt_distribution()
            top, bot, stats = self._realisation_stats(dep, tau, tilt)
            vf, n_cell = dep.volume_fraction(), len(dep)
        else:
            na, tau = self._volume_numbers()
            tilt, top, bot = fl.tilt_distribution(), 0.0, 1.0
            vf, n_cell = float(fl.fraction), int(round(na * self.cell_nm[0] * self.cell_nm[1]))
        over = []
        if self.optical_depth is not None:
            tau = float(self.optical_depth)
            over.append("optical_depth")
        if self.tilt_deg is not None:
            tilt = gaussian_tilt(float(self.tilt_deg))
            over.append("tilt_deg")
        proj = tau * float(tilt.projected_mean(1.0))
        out = DerivedFlakeLayer(na * 1e12, float(tau), proj, tilt, tilt.mean_tilt_deg(), (top, max(bot, top + 1e-6)),
                                float(vf), int(n_cell), self.derive, tuple(over),
                                stats if self.derive == "deposit" else {})
        self._memo["derived"] = out
        return out

    # -- optics ------------------------------------------------------------------------
    def n_binder(self) -> float:
        """Real index of the binder at 550 nm (the flakes' surrounding medium)."""
        return float(np.real(np.asarray(_nk(self.binder, np.array([550.0])), complex)[0]))

    def pigment_optics(self, wavelength_nm):
        """μa, μs, g of the pigments in the binder between the flakes
        (:func:`nmmm.layers.pigment_mixture.mixture_optics`), or None without pigments."""
        if not self.pigments:
            return None
        from nmmm.layers.pigment_mixture import mixture_optics

        return mixture_optics(self.pigments, self.binder, as_wavelength_nm(np.atleast_1d(wavelength_nm)))

    def _body_without_medium(self, w, mix):
        """Fallback when the BRDF has no pigmented-medium input: the pigments as a
        Kubelka–Munk film of the coat's thickness over the substrate (a Lambertian base)."""
        from nmmm.layers.kubelka_munk import km_coefficients, km_reflectance

        sub = _on_grid(self.substrate_reflectance, w)
        if mix is None:
            return (w, sub)
        K, S = km_coefficients(mix.mu_a_per_nm, mix.mu_s_per_nm, mix.g)
        return (w, np.clip(np.asarray(km_reflectance(K, S, float(self.coat_thickness_nm), sub), float), 0, 1))

    def brdf(self, wavelength_nm=None):
        """``(PaintBRDF, FlakeList)``: the statistical BRDF (multi-angle colour, renderer) and
        the discrete flakes of one cell (glints, sparkle), from the same derived layer.
        ``wavelength_nm`` (default 380–780 nm by 10 nm) is the grid of the pigments' optics."""
        from nmmm.appearance.brdf import ClearCoat, PaintBRDF
        from nmmm.appearance.flakes import FlakeLayer

        w = as_wavelength_nm(np.arange(380.0, 781.0, 10.0) if wavelength_nm is None else np.atleast_1d(wavelength_nm))
        d = self.derived()
        optics = self.flakes.optics()
        kw = {}
        if "depth_range" in inspect.signature(FlakeLayer).parameters:
            kw["depth_range"] = d.depth_range
        fl = self.flakes
        if "surface_roughness" in inspect.signature(FlakeLayer).parameters:
            from nmmm.appearance.flakes import edge_scatter_fraction

            kw["surface_roughness"] = float(fl.face_roughness)
            w_e = float(fl.edge_width_nm)
            kw["edge_fraction"] = edge_scatter_fraction(float(fl.diameter_um) * 1e3, w_e) if w_e > 0 else 0.0
        layer = FlakeLayer(optics, d.tilt, d.optical_depth, **kw)
        mix = self.pigment_optics(w)
        coat = ClearCoat(self.binder, self.roughness)
        medium = _coat_medium(mix, float(self.coat_thickness_nm)) if mix is not None else None
        if medium is not None:
            paint = PaintBRDF(coat, _on_grid_pair(self.substrate_reflectance, w), layer, medium=medium, name=self.name)
        else:
            paint = PaintBRDF(coat, self._body_without_medium(w, mix), layer, name=self.name)
        return paint, self.flake_list()

    @classmethod
    def from_sem(cls, stats: dict, coat_thickness_nm: float, material="aluminium", **kw) -> "EffectCoat":
        """An effect coat whose flakes are the statistics measured on SEM cross-sections
        (the dict of :func:`nmmm.microstructure.estimate_flakes`): mean/std diameter,
        thickness, rms tilt (the half-normal scale s has E[θ²] = s²) and flakes per mm²
        (→ volume fraction φ = N_A π⟨D²⟩/4 · t / H)."""
        try:
            md, sd = float(stats["mean_diameter_nm"]), float(stats["std_diameter_nm"])
            t, rms = float(stats["thickness_nm"]), float(stats["tilt_rms_deg"])
            na = float(stats["number_density_per_mm2"]) * 1e-12
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"SEM statistics need mean_diameter_nm, std_diameter_nm, thickness_nm, tilt_rms_deg "
                                    f"and number_density_per_mm2 (estimate_flakes' keys); {exc}") from None
        H = _num(coat_thickness_nm, "coat_thickness_nm", 0.0)
        phi = na * math.pi / 4 * (md * md + sd * sd) * t / H
        spec = FlakeSpec(material, md / 1e3, sd / 1e3, t, phi, rms, name=kw.pop("flake_name", ""))
        return cls(spec, coat_thickness_nm=H, **kw)

    def __repr__(self):
        return (f"<EffectCoat '{self.name}': {self.flakes.fraction:g} flakes ({self.flakes.diameter_um:g} µm × "
                f"{float(self.flakes.thickness_nm):g} nm), {len(self.pigments)} pigment(s), "
                f"{self.coat_thickness_nm / 1e3:g} µm, derive={self.derive}>")


def _on_grid(v, w):
    if isinstance(v, tuple) and len(v) == 2:
        return np.interp(w, np.asarray(v[0], float), np.asarray(v[1], float))
    return np.broadcast_to(np.asarray(v, float), w.shape).astype(float)


def _on_grid_pair(v, w):
    return v if np.ndim(v) == 0 else (w, _on_grid(v, w))


def _coat_medium(mix, thickness_nm):
    """The BRDF's pigmented-coat input (helper H's ``CoatMedium``) when it exists."""
    try:
        from nmmm.appearance.brdf import CoatMedium, PaintBRDF
    except ImportError:
        return None
    if "medium" not in inspect.signature(PaintBRDF).parameters:
        return None
    return CoatMedium(mix.wavelength_nm, mix.mu_a_per_nm, mix.mu_s_per_nm, mix.g, thickness_nm)
