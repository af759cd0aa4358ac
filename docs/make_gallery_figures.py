"""Regenerate the stored gallery figures (docs/gallery_figures/<example>/*.png) of the examples the
docs build does not run (conf.py's nmmm_gallery_run lists those it runs): each example is run into a
scratch folder and its PNGs (at most 6, sorted by name) are copied. Run: python docs/make_gallery_figures.py"""

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS))
from conf import nmmm_gallery_run  # noqa: E402

for ex in sorted((ROOT / "examples").glob("*.py")):
    if ex.stem in nmmm_gallery_run or len(sys.argv) > 1 and ex.stem not in sys.argv[1:]:
        continue
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT / "src")}
        try:
            r = subprocess.run([sys.executable, str(ex), str(Path(tmp) / "out")], cwd=tmp, env=env,
                               capture_output=True, text=True, timeout=300)
        except subprocess.TimeoutExpired:
            print(f"{ex.stem}: over 300 s, skipped")
            continue
        pngs = sorted(Path(tmp).rglob("*.png"))[:6]
        dest = DOCS / "gallery_figures" / ex.stem
        shutil.rmtree(dest, ignore_errors=True)
        if pngs:
            dest.mkdir(parents=True)
            for p in pngs:
                shutil.copy(p, dest / p.name)
        print(f"{ex.stem}: exit {r.returncode}, {len(pngs)} figures")
