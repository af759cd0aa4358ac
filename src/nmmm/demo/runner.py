"""``nmmm demo``: the seed paper's worked examples, from the shipped recipes and the demo
hooks of :mod:`nmmm.demo`, into one self-contained HTML report.

- :func:`run_sections` — runs every section of :mod:`nmmm.demo.sections`, each guarded: a failing
  section becomes an error box in the report and the others go on. Returns a :class:`DemoRun`
  (report path, one :class:`SectionFailure` per failed section, skipped titles).
- :func:`run_demo` — the same, returning ``(report_path, failed_titles, skipped_titles)``.
- :func:`failure_hint` — what to install when an exception says a package or system library is
  missing (``pip install h5py``, ``apt-get install libllvm19``, ``apt-get install chromium``).

A hook whose module does not exist (a package not yet written) is listed as "not
available" and does not count as a failure; any other exception does.
"""

from __future__ import annotations

import importlib
import inspect
import re
import time
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

from nmmm.demo import sections
from nmmm.recipes.report import error_section, hook_section, result_section, write_report

__all__ = ["run_demo", "run_sections", "DemoRun", "SectionFailure", "failure_hint", "demo_next_steps"]


@dataclass(frozen=True)
class SectionFailure:
    """One failed section: its title, the exception's last line and what to do about it."""

    title: str
    target: str
    error: str
    hint: str = ""


@dataclass(frozen=True)
class DemoRun:
    """The outcome of :func:`run_sections`."""

    report: Path
    failures: list = field(default_factory=list)
    skipped: list = field(default_factory=list)

    @property
    def failed(self) -> list[str]:
        """Titles of the failed sections."""
        return [f.title for f in self.failures]


#: import name -> distribution to ``pip install`` where they differ
PIP_NAMES = {
    "PIL": "pillow", "skimage": "scikit-image", "yaml": "pyyaml", "colour": "colour-science",
    "OpenEXR": "openexr", "Imath": "openexr", "sklearn": "scikit-learn", "drjit": "mitsuba",
    "distributed": "'dask[distributed]'", "multipart": "python-multipart", "tomli_w": "tomli-w",
}
LIBLLVM_HINT = "apt-get install libllvm19"
CHROMIUM_HINT = "apt-get install chromium"
_NO_MODULE = re.compile(r"No module named '([\w.]+)'")


def _chain(exc: BaseException):
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        yield exc
        exc = exc.__cause__ or exc.__context__


def failure_hint(exc: BaseException) -> str:
    """The install command for a missing optional package or system library named by ``exc``
    (or any exception it was raised from); "" when it names none."""
    chain = list(_chain(exc))
    for e in chain:  # a missing Python package: the first one named
        name = getattr(e, "name", None) if isinstance(e, ImportError) else None
        if not name:
            m = _NO_MODULE.search(str(e))
            name = m.group(1) if m else None
        if name:
            top = name.split(".")[0]
            if top != "nmmm":
                return f"pip install {PIP_NAMES.get(top, top)}"
    text = " ".join(f"{type(e).__name__}: {e}" for e in chain)
    if re.search(r"libLLVM|LLVM|Dr\.?Jit|drjit|Mitsuba", text):
        return LIBLLVM_HINT
    if re.search(r"chromium|chrome", text, re.IGNORECASE):
        return CHROMIUM_HINT
    return ""


def _last_line(exc: BaseException) -> str:
    lines = traceback.format_exception_only(type(exc), exc)
    last = "".join(lines).strip().splitlines()
    return last[-1] if last else type(exc).__name__


def _recipe_section(name, out, progress):
    from nmmm.recipes.run import run_recipe
    from nmmm.recipes.schema import example_path

    if name == "substitution":
        from nmmm.recipes.compare import compare_recipes

        a, b = sections.SUBSTITUTION
        r = compare_recipes(example_path(a), example_path(b), out / "substitution", illuminants=["D65", "A"],
                            progress=progress)
        sec = r["section"]
        sec["title"] = f"Substitution (nmmm compare): {r['a'].recipe.name} → {r['b'].recipe.name}"
        sec["text"] = [f"The binder of the hematite paint substituted: epoxy → ethylcellulose, everything else "
                       f"unchanged — the colour difference seen before anything is made."] + sec["text"]
        sec["next"] = [("reproduce this section", f"nmmm compare {a} {b} -i D65 -i A -o {out / 'substitution'}"),
                       ("start your own substitution from the second recipe", f"cp {example_path(b)} my_substitute.toml"),
                       ("then compare it with the original", f"nmmm compare {a} my_substitute.toml -i D65 -i A -o compare-out")]
        return sec

    res = run_recipe(example_path(name), out / name, progress=progress, report=False)
    sec = result_section(res, source=str(example_path(name)), command=f"nmmm run {name} -o {out / name}")
    if name == "hematite_paint":
        _hematite_series(example_path(name), out / name, sec, progress)
    return sec


def _hematite_series(path, out, sec, progress):
    """The 5/7/10 % and grain-size series: serial sweeps of the shipped recipe."""
    from nmmm.recipes.sweep import sweep

    fractions, diagonals = sections.HEMATITE_FRACTIONS, sections.HEMATITE_DIAGONALS_NM
    fr = sweep(path, [("pigment.fraction", list(fractions)), ("pigment.dependent_scattering", [False, True])],
               out / "fraction_series", serial=True, progress=progress)
    gs = sweep(path, [("pigment.body_diagonal_nm", list(diagonals))], out / "grain_size_series",
               serial=True, progress=progress)
    cols = lambda df, p, head: [{head: r[f"param:{p}"], "L": r["L_D65"], "a": r["a_D65"], "b": r["b_D65"]}
                                for _, r in df.iterrows()]
    sec["tables"]["Volume fraction series (CIELAB, D65)"] = [
        {"fraction (1)": r["param:pigment.fraction"], "packing (Percus-Yevick)": bool(r["param:pigment.dependent_scattering"]),
         "L": r["L_D65"], "a": r["a_D65"], "b": r["b_D65"]} for _, r in fr["results"].iterrows()]
    sec["tables"]["Grain-size series at 7 % (CIELAB, D65)"] = cols(gs["results"], "pigment.body_diagonal_nm", "body diagonal (nm)")
    sec["figures"] += [fr.get("plot"), gs.get("plot")]
    L = list(gs["results"]["L_D65"])
    trend = "darker" if L[-1] < max(L) else "not darker"
    from nmmm.recipes.sanity import masstone_unchanged_note
    from nmmm.recipes.schema import load_recipe

    film_um = load_recipe(path).film.thickness_nm / 1000.0
    ind = fr["results"][~fr["results"]["param:pigment.dependent_scattering"].astype(bool)]
    note = masstone_unchanged_note(ind["param:pigment.fraction"], ind[["L_D65", "a_D65", "b_D65"]].to_numpy(float),
                                   film_um)
    if note:
        sec.setdefault("warnings", []).append(note + " Here only packing (Percus-Yevick dependent scattering) "
                                              "separates 5, 7 and 10 %.")
    else:
        sec["text"].append("Packing (Percus-Yevick dependent scattering) changes the colour further at 7 and 10 %.")
    sec["text"].append(f"Series (serial sweeps of this recipe): 5/7/10 % by volume, and body diagonals "
                       f"{', '.join(f'{d:g}' for d in diagonals)} nm at 7 %. Beyond the lightest size "
                       f"(L* = {max(L):.1f} at {diagonals[L.index(max(L))]:g} nm) bigger grains look {trend}: "
                       f"L* = {L[-1]:.1f} at {diagonals[-1]:g} nm.")


def _accepts_progress(fn) -> bool:
    """Whether a hook takes a ``progress`` keyword (hooks that draw tqdm bars do)."""
    try:
        params = inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False
    return "progress" in params


def _hook_section(title, target, out, progress=True):
    module_name, fn = target.split(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and (module_name == exc.name or module_name.startswith(exc.name + ".")):
            return None  # package not written yet
        raise
    hook = getattr(module, fn)
    kw = {"progress": progress} if _accepts_progress(hook) else {}
    summary = hook(out / module_name.replace(".", "_"), **kw)
    sec = hook_section(summary)
    sec["title"] = summary.get("title") or title
    sec["next"] = sec.get("next") or [("reproduce this section",
                                       f"nmmm demo --only {module_name} -o {out / module_name.replace('.', '_')}")]
    return sec


def run_sections(output_dir="nmmm-demo", quick: bool = False, only=None, progress: bool = True) -> DemoRun:
    """Run the demo into ``output_dir``; returns a :class:`DemoRun`.

    ``quick`` runs the shipped recipes only (no demo hooks); ``only`` restricts to
    sections whose recipe name or hook target contains one of the given strings.
    """
    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    jobs = [(name, "recipe", name) for name in sections.RECIPE_SECTIONS]
    if not quick:
        jobs += [(title, "hook", target) for title, target in sections.HOOKS]
    if only:
        jobs = [j for j in jobs if any(o in j[2] or o.lower() in j[0].lower() for o in only)]
    secs, failures, skipped = [], [], []
    for title, kind, target in jobs:
        t0 = time.perf_counter()
        if progress:
            print(f"[nmmm demo] {title} ...", flush=True)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sec = _recipe_section(target, out, progress) if kind == "recipe" else _hook_section(title, target, out, progress)
            if sec is None:
                skipped.append(title)
                continue
            sec["elapsed_s"] = time.perf_counter() - t0
            if kind == "recipe" and not sec["title"].startswith("Substitution"):
                sec["title"] = f"Recipe: {sec['title']}"
        except Exception as exc:  # noqa: BLE001 - one failing package must not kill the demo
            tb = traceback.format_exc(limit=6)
            sec = error_section(f"{title} ({target})", f"{type(exc).__name__}: {exc}\n\n{tb}",
                                time.perf_counter() - t0)
            failures.append(SectionFailure(title, target, _last_line(exc), failure_hint(exc)))
        secs.append(sec)
    intro = ("The worked examples of the seed paper, each computed from its compounds' optical constants: "
             "first from the TOML recipes shipped with nmmm (nmmm run), then the packages' own worked examples.")
    if skipped:
        intro += " Not available in this installation: " + ", ".join(skipped) + "."
    report = write_report(secs, out / "report.html", title="nmmm demo — the seed paper's worked examples",
                          intro=intro, next_steps=demo_next_steps())
    return DemoRun(Path(report), failures, skipped)


def demo_next_steps() -> list[tuple[str, str]]:
    """The three commands a formulator uses after the demo: run an own recipe (copied from a
    shipped one), compare it with the original, sweep one of its parameters."""
    from nmmm.recipes.schema import example_path

    src = example_path("hematite_paint")
    return [(f"start from a shipped recipe — copy it (cp {src} my_paint.toml), change the pigment, binder or film "
             "in it, and run it: spectra, CIELAB, plots and a report", "nmmm run my_paint.toml -o out/my_paint"),
            ("see what your change does against the original, under daylight and incandescent light",
             "nmmm compare hematite_paint my_paint.toml -i D65 -i A -o out/compare"),
            ("find the amount that gives the colour you want: sweep one parameter (resumable; add --vary for a grid)",
             "nmmm sweep my_paint.toml --vary pigment.fraction=0.03:0.15:5 --serial -o out/sweep")]


def run_demo(output_dir="nmmm-demo", quick: bool = False, only=None, progress: bool = True):
    """Run the demo into ``output_dir``; returns ``(report_path, failed, skipped)`` (lists of titles).

    ``quick`` runs the shipped recipes only (no demo hooks); ``only`` restricts to
    sections whose recipe name or hook target contains one of the given strings.
    """
    r = run_sections(output_dir, quick=quick, only=only, progress=progress)
    return r.report, r.failed, r.skipped
