"""Common paint binders as dispersion models, each with its published source.

- :data:`BINDERS` — epoxy, acrylic, alkyd, polyurethane, nitrocellulose, ethylcellulose as
  :class:`BinderEntry` (chemistry, status of the published data, source, notes).
- :func:`binder` — the Material of a binder by name or synonym (``"PMMA"`` → acrylic).
- :func:`find_binders` — the entries whose name, synonyms or chemistry contain a text.

Only published parameters are shipped. Where a dispersion model is published it is used as
published (the refractiveindex.info entry that holds it, evaluated by
:mod:`nmmm.materials.database`); where only the sodium-D index n_D is published the binder is a
non-dispersive :class:`~nmmm.materials.material.Constant` and says so; where nothing is published
in a source available here, the entry has no model and :func:`binder` raises
:class:`~nmmm.errors.MaterialNotFoundError` saying what to do. No binder here gives an absorption
k (all are k = 0): a binder "slightly absorbing in the red" must be modelled in the recipe.

References
----------
- MicroChem, *SU-8 2000 Permanent Epoxy Negative Photoresist*, data sheet (2011): Cauchy
  n = 1.566 + 0.00796/λ² + 0.00014/λ⁴ (λ in µm), 320–800 nm; refractiveindex.info
  ``other/Microchem_SU8_2000/specs``.
- N. Sultanova, S. Kasarova, I. Nikolov, "Dispersion properties of optical polymers",
  Acta Phys. Pol. A 116, 585–587 (2009): PMMA, Sellmeier n² − 1 = 1.1819 λ²/(λ² − 0.011313)
  (λ in µm), 437–1052 nm; refractiveindex.info ``organic/poly_methyl_methacrylate/Sultanova``.
- J. Brandrup, E. H. Immergut, E. A. Grulke (eds.), *Polymer Handbook*, 4th ed., Wiley (1999),
  ch. VI: ethyl cellulose n_D = 1.479.
- M. N. Polyanskiy, Sci. Data 11, 94 (2024), https://doi.org/10.1038/s41597-023-02898-2
"""

from __future__ import annotations

from dataclasses import dataclass

from nmmm.errors import InvalidInputError, MaterialNotFoundError
from nmmm.materials.material import Constant, Material

__all__ = ["BINDERS", "BinderEntry", "binder", "find_binders"]


@dataclass(frozen=True)
class BinderEntry:
    """One binder of :data:`BINDERS`.

    ``status`` is ``"dispersion"`` (a published dispersion model, ``database_key`` holds it),
    ``"n_D only"`` (``n_d`` at 589.3 nm only: non-dispersive) or ``"not published"`` (no model).
    """

    name: str
    synonyms: tuple[str, ...]
    chemistry: str
    status: str
    reference: str
    notes: str
    database_key: str | None = None
    n_d: float | None = None

    def material(self) -> Material:
        """The binder's Material (raises :class:`MaterialNotFoundError` when nothing is published)."""
        if self.database_key is not None:
            from nmmm.materials.database import get

            return get(self.database_key)
        if self.n_d is not None:
            return Constant(self.n_d, name=f"{self.name} (n_D {self.n_d:g}, non-dispersive)",
                            reference=f"{self.reference} (n_D only)")
        raise MaterialNotFoundError(
            f"no published dispersion model of {self.name} ({self.chemistry}) is shipped: {self.notes} "
            "Give the binder in the recipe instead, e.g. [compounds.binder] model = \"cauchy\" with the "
            "A, B, C of your own measurement (ellipsometry: nmmm ellipsometry fit), or n = <measured n_D>.")

    @property
    def range_nm(self) -> tuple[float, float] | None:
        """Where the published model holds (``None`` without a model)."""
        try:
            return self.material().range_nm
        except MaterialNotFoundError:
            return None


BINDERS: dict[str, BinderEntry] = {b.name: b for b in (
    BinderEntry(
        "epoxy", ("epoxy resin", "su-8", "bisphenol a epoxy"), "bisphenol-A novolac epoxy (SU-8, uncured)",
        "dispersion", "MicroChem SU-8 2000 data sheet (2011), via refractiveindex.info",
        "SU-8 is a photoresist epoxy; cured paint epoxies (bisphenol-A/epichlorohydrin with an amine "
        "hardener) differ by a few 0.01 in n. Cauchy n only (k = 0), 320–800 nm.",
        database_key="other/Microchem_SU8_2000/specs"),
    BinderEntry(
        "acrylic", ("pmma", "poly(methyl methacrylate)", "acrylic resin", "plexiglas"),
        "poly(methyl methacrylate) (PMMA)", "dispersion",
        "N. Sultanova, S. Kasarova, I. Nikolov, Acta Phys. Pol. A 116, 585 (2009), via refractiveindex.info",
        "Acrylic paint binders are copolymers of MMA with other acrylates; PMMA stands for them. The "
        "published fit holds for 437–1052 nm only: below 437 nm pass extrapolate=True knowingly, or use "
        "organic/poly_methyl_methacrylate/Szczurowski (405–1083 nm).",
        database_key="organic/poly_methyl_methacrylate/Sultanova"),
    BinderEntry(
        "ethylcellulose", ("ethyl cellulose", "ec"), "cellulose ethyl ether", "n_D only",
        "J. Brandrup, E. H. Immergut, E. A. Grulke, Polymer Handbook, 4th ed. (Wiley 1999)",
        "Only n_D = 1.479 is published there; no dispersion (the shipped recipe "
        "hematite_paint_ethylcellulose adds an assumed Cauchy B, and says so).", n_d=1.479),
    BinderEntry(
        "alkyd", ("alkyd resin", "oil-modified polyester"), "oil-modified polyester", "not published",
        "-", "No dispersion model or n_D of alkyd resins is in refractiveindex.info, and the values "
        "quoted in trade literature vary with the oil length; none is shipped."),
    BinderEntry(
        "polyurethane", ("pu", "urethane", "2k polyurethane"), "polyurethane (isocyanate-polyol)", "not published",
        "-", "No dispersion model of a polyurethane coating resin is in refractiveindex.info "
        "(Norland NOA adhesives are thiol-ene, not polyurethanes); none is shipped."),
    BinderEntry(
        "nitrocellulose", ("cellulose nitrate", "nc", "nitrocellulose lacquer"), "cellulose nitrate",
        "not published", "-", "No dispersion model of cellulose nitrate is in refractiveindex.info "
        "(organic/cellulose/Sultanova is cellulose itself, not the nitrate); none is shipped."),
)}


def _lookup() -> dict[str, BinderEntry]:
    out = {}
    for b in BINDERS.values():
        for n in (b.name,) + b.synonyms:
            out[n.lower()] = b
    return out


def binder(name: str) -> Material:
    """The Material of binder ``name`` (a key of :data:`BINDERS` or a synonym, case-insensitive).

    >>> binder("PMMA").name
    'organic/poly_methyl_methacrylate/Sultanova'
    >>> round(float(binder("epoxy").n(589.3)), 4)
    1.5901
    """
    if not isinstance(name, str):
        raise InvalidInputError(f"binder name must be a string, e.g. 'epoxy', got {name!r}")
    entry = _lookup().get(name.strip().lower())
    if entry is None:
        raise MaterialNotFoundError(f"unknown binder {name!r}; the table has {sorted(BINDERS)} "
                                    "(and their synonyms, e.g. 'PMMA')")
    return entry.material()


def find_binders(text: str) -> list[BinderEntry]:
    """Entries of :data:`BINDERS` whose name, synonyms or chemistry contain ``text`` (case-insensitive)."""
    t = text.strip().lower()
    return [b for b in BINDERS.values()
            if any(t in s.lower() for s in (b.name, b.chemistry) + b.synonyms)]
