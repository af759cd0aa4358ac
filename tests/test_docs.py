"""The documentation (issue 23 item 1): ``docs/`` builds offline with Sphinx with warnings as errors
(``-W --keep-going``), and in Debian's chromium every internal link of every page reachable from the
built index resolves (the file exists, and the ``#anchor`` is an id on that page), every image loads,
and the generated recipe reference lists the schema's keys.

The build copies ``docs/`` into a temporary folder (the gallery is generated there), runs four quick
examples and takes ~1-2 min on 2 cores."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path
from urllib.parse import unquote, urldefrag, urlparse

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = Path("/usr/bin/chromium")


@pytest.fixture(scope="module")
def built_docs(tmp_path_factory):
    pytest.importorskip("sphinx")
    tmp = tmp_path_factory.mktemp("docs")
    src = tmp / "repo" / "docs"
    # the conf and the gallery find examples/ and src/ next to docs/: lay the same tree out
    shutil.copytree(ROOT / "docs", src, ignore=shutil.ignore_patterns("_build", "gallery"))
    (tmp / "repo" / "examples").symlink_to(ROOT / "examples")
    (tmp / "repo" / "src").symlink_to(ROOT / "src")
    shutil.copy(ROOT / "CHANGELOG.md", tmp / "repo" / "CHANGELOG.md")
    out = tmp / "html"
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-W", "--keep-going", "-q", str(src), str(out)],
                          capture_output=True, text=True, timeout=480)
    assert proc.returncode == 0, f"sphinx-build -W failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-6000:]}"
    return out


def test_recipe_reference_is_generated_from_the_schema(built_docs):
    from nmmm.recipes.schema import Recipe

    html = (built_docs / "recipe_reference.html").read_text(encoding="utf-8")
    for key in Recipe.model_fields:
        assert f">{key}<" in html or f"{key}</span>" in html, key
    for key in ("pigment.fraction", "film.thickness_nm", "spectral.step_nm"):
        assert key in html
    # the explicit units of dispersion coefficients (issue 25 item 4), from the same table the code reads
    from nmmm.materials.models import EXPLICIT_UNIT_KEYS

    assert "Units of dispersion-model coefficients" in html
    for keys in EXPLICIT_UNIT_KEYS.values():
        for key in keys:
            assert f">{key}<" in html, key
    assert "µm²" in html and "nm⁴" in html


@pytest.mark.browser
@pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium at /usr/bin/chromium")
def test_every_internal_link_resolves_in_chromium(built_docs):
    from playwright.sync_api import sync_playwright

    root = built_docs.resolve()
    index = root / "index.html"
    seen: dict[Path, set[str]] = {}
    links: list[tuple[Path, Path, str]] = []
    broken_images: list[str] = []
    todo = [index]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=["--no-sandbox"])
        page = browser.new_page()
        while todo:
            f = todo.pop()
            if f in seen:
                continue
            page.goto(f.as_uri())
            seen[f] = set(page.eval_on_selector_all("[id]", "els => els.map(e => e.id)"))
            for img in page.eval_on_selector_all("img", "els => els.map(e => [e.src, e.complete && e.naturalWidth > 0])"):
                if not img[1]:
                    broken_images.append(f"{f.relative_to(root)}: {img[0]}")
            for href in page.eval_on_selector_all("a[href]", "els => els.map(e => e.href)"):
                u = urlparse(href)
                if u.scheme != "file":
                    continue  # external (none is needed offline) or mailto
                path, frag = urldefrag(href)
                target = Path(unquote(urlparse(path).path))
                links.append((f, target, frag))
                if target.suffix == ".html" and target.exists() and root in target.parents:
                    todo.append(target)
        browser.close()
    missing = [f"{a.relative_to(root)} -> {t}" for a, t, _ in links if not t.exists()]
    bad_anchor = [f"{a.relative_to(root)} -> {t.name}#{frag}" for a, t, frag in links
                  if frag and t.exists() and t.suffix == ".html" and frag not in seen.get(t, set())]
    assert len(seen) > 30, f"only {len(seen)} pages reachable from the index"
    assert not missing, f"{len(missing)} links to missing files, e.g. {missing[:10]}"
    assert not bad_anchor, f"{len(bad_anchor)} links to missing anchors, e.g. {bad_anchor[:10]}"
    assert not broken_images, broken_images[:10]
    gallery = [f for f in seen if f.parent.name == "gallery" and f.name != "index.html"]
    assert len(gallery) >= 10  # one page per example


@pytest.mark.browser
@pytest.mark.skipif(not CHROMIUM.exists(), reason="needs Debian's chromium at /usr/bin/chromium")
def test_gallery_description_wraps_inside_its_box(built_docs):
    """Each gallery page's description (the example's docstring, as text) wraps at the body's width at
    1366 px: no line of it runs past its box or needs a scroll bar (the listing below may scroll)."""
    from playwright.sync_api import sync_playwright

    pages = sorted((built_docs / "gallery").glob("*.html"))
    pages = [f for f in pages if f.name != "index.html"]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1366, "height": 900})
        bad = []
        for f in pages:
            page.goto(f.resolve().as_uri())
            info = page.evaluate("""() => {
                const box = document.querySelector('div.nmmm-description');
                if (!box) return null;
                const pre = box.querySelector('pre');
                const body = document.querySelector('div.body').getBoundingClientRect();
                return {scroll: pre.scrollWidth - pre.clientWidth, right: box.getBoundingClientRect().right - body.right,
                        text: pre.innerText, page: document.documentElement.scrollWidth};
            }""")
            if info is None or info["scroll"] > 1 or info["right"] > 1 or info["page"] > 1366 or "``" in info["text"]:
                bad.append((f.name, info and {k: v for k, v in info.items() if k != "text"}))
        browser.close()
    assert len(pages) >= 10 and bad == []
