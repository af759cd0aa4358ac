"""Write the small input files that the README's command lines use (``examples/data/``).

Every file here is *synthetic*, made by nmmm itself from a known truth, so that a command run
on it can be checked against that truth:

- ``epoxy_on_si.csv`` — Ψ, Δ of a 523.4 nm Cauchy epoxy film (SU-8: A = 1.566, B = 0.00796 µm²,
  C = 0.00014 µm⁴) on silicon (Green 2008), 350–1000 nm every 5 nm at 55°, 65° and 75°,
  computed with :mod:`nmmm.ellipsometry`'s forward model plus Gaussian noise σΨ = 0.02°,
  σΔ = 0.05° (seed 14) — a good spectroscopic ellipsometer's repeatability.
- ``epoxy_on_si.toml`` — the model to fit to it (start values away from the truth); written by
  hand, not by this script.
- ``hardcore_cell.toml`` — a microstructure for ``nmmm micro generate`` (written by hand).
- ``sem_hardcore.png`` — a 256 × 256 SEM-like image (10 nm pixels) of a hard-core section:
  discs of radius 60 nm at area fraction 0.15 with a 20 nm exclusion shell, blurred (σ 1 px)
  with Gaussian noise σ 0.06 on a contrast of 0.5 (grey 0.25 matrix, 0.75 particles).
- ``pairs.toml`` and ``pairs/*.png`` — two stimulus pairs for ``nmmm experiment serve``:
  smooth colour gradients with grain, stand-ins for a rendering and a photograph.
- ``responses.sqlite`` — the responses of 20 *simulated* observers (not data) to that
  experiment, for ``nmmm experiment stats``.

Run from anywhere: ``python examples/data/make_example_data.py [OUTPUT_DIR]`` (default: the
folder of this script). The output is deterministic, except the timestamps in
responses.sqlite.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

TRUTH = {"thickness_nm": 523.4, "A": 1.566, "B": 0.00796, "C": 0.00014}
TRUTH_TOML = """\
name = "epoxy on silicon (truth)"
ambient = 1.0
[substrate]
material = "main/Si/Green-2008"
[[layers]]
name = "epoxy"
thickness_nm = {thickness_nm}
model = "cauchy"
A = {A}
B = {B}
C = {C}
"""


def ellipsometry_csv(out: Path) -> Path:
    """Ψ/Δ of the known epoxy film on silicon, with noise, as a plain CSV."""
    from nmmm.ellipsometry.data import EllipsometryData, write_csv
    from nmmm.ellipsometry.model import read_model

    with tempfile.TemporaryDirectory() as tmp:
        truth = Path(tmp) / "truth.toml"
        truth.write_text(TRUTH_TOML.format(**TRUTH))
        model = read_model(truth)
    w = np.arange(350.0, 1000.1, 5.0)
    data = EllipsometryData.from_model(model.build(), w, np.array([55.0, 65.0, 75.0]), 0.02, 0.05,
                                       noise_seed=14, name="synthetic epoxy on Si")
    path = write_csv(data, out / "epoxy_on_si.csv")
    header = ("# SYNTHETIC data made by examples/data/make_example_data.py with nmmm's forward model:\n"
              f"# epoxy film {TRUTH['thickness_nm']} nm, Cauchy A = {TRUTH['A']}, B = {TRUTH['B']} um^2, "
              f"C = {TRUTH['C']} um^4, on main/Si/Green-2008;\n"
              "# Gaussian noise sigma_psi = 0.02 deg, sigma_delta = 0.05 deg (seed 14).\n")
    path.write_text(header + path.read_text())
    return path


def sem_image(out: Path) -> Path:
    """A blurred, noisy section of a hard-core disc model as an 8-bit PNG."""
    from PIL import Image
    from scipy import ndimage

    from nmmm.microstructure.hardcore import hardcore_spheres

    m = hardcore_spheres((256, 256), 10.0, 60.0, 0.15, exclusion_nm=20.0, seed=3)
    rng = np.random.default_rng(5)
    img = 0.25 + 0.5 * ndimage.gaussian_filter(m.labels.astype(float), 1.0) + rng.normal(0, 0.12 * 0.5, m.shape)
    path = out / "sem_hardcore.png"
    Image.fromarray((np.clip(img, 0, 1) * 255).round().astype(np.uint8)).save(path, optimize=True)
    return path


def pairs(out: Path) -> Path:
    """Two stand-in stimulus pairs and their ``pairs.toml``."""
    from PIL import Image

    from nmmm.experiment.pairs import make_pairs_file

    img_dir = out / "pairs"
    img_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    size = 96
    y, x = np.mgrid[0:size, 0:size] / size
    triples = []
    for i, label in enumerate(("plate 1", "plate 2")):
        base = rng.uniform(0.25, 0.75, 3)
        tilt = rng.uniform(-0.2, 0.2, 3)
        smooth = np.clip(base + tilt * ((x + y) / 2)[..., None], 0, 1)
        photo = np.clip(smooth + rng.normal(0, 0.03, smooth.shape), 0, 1)
        render = np.clip(smooth + rng.normal(0, 0.02, smooth.shape), 0, 1)
        p_photo, p_render = img_dir / f"plate{i + 1}_photo.png", img_dir / f"plate{i + 1}_render.png"
        Image.fromarray((photo * 255).round().astype(np.uint8)).save(p_photo, optimize=True)
        Image.fromarray((render * 255).round().astype(np.uint8)).save(p_render, optimize=True)
        triples.append((p_render, p_photo, label))
    return make_pairs_file(triples, out / "pairs.toml", repetitions=5, viewing_distance_cm=50)


def responses(out: Path, pairs_toml: Path) -> Path:
    """20 simulated observers (not data) answering the experiment of ``pairs_toml``."""
    from nmmm.experiment.pairs import load_pairs

    from nmmm.experiment.simulation import simulate_responses

    db = out / "responses.sqlite"
    for suffix in ("", "-wal", "-shm"):
        Path(f"{db}{suffix}").unlink(missing_ok=True)
    simulate_responses(load_pairs(pairs_toml), db, n_observers=20, mean_pc=0.55, rho=0.05, seed=7)
    import sqlite3

    with sqlite3.connect(db) as con:  # one self-contained file: no -wal/-shm beside it
        con.execute("PRAGMA journal_mode=DELETE")
        con.execute("VACUUM")
    return db


def main(out_dir=None) -> list[Path]:
    out = Path(out_dir) if out_dir else Path(__file__).resolve().parent
    out.mkdir(parents=True, exist_ok=True)
    toml = pairs(out)
    written = [ellipsometry_csv(out), sem_image(out), toml, responses(out, toml)]
    for p in written:
        print(f"wrote {p} ({p.stat().st_size / 1024:.0f} kB)")
    return written


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else None)
