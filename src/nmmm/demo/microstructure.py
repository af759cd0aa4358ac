"""Worked example of the microstructure scale (the seed's hematite and metallic paints).

- :func:`demo` — writes into ``output_dir``:

  1. sections of hard-core models of hematite pseudo-cubes (250 nm large diagonal,
     random orientations) in epoxy at 5, 7 and 10 % (SEM-like images);
  2. the analysis of the 7 % section with detected particles and exclusion zones (as the
     seed's Figure 8) and the estimated parameters against the true ones;
  3. a metallic-paint flake deposit in the seed's 450 µm × 450 µm × 20 µm cell: top view,
     a vertical cut, tilt and depth histograms;
  4. an RVE study of the hematite volume fraction (Kanit et al. 2003);

  and returns ``{"title", "figures", "tables", "text"}``.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

__all__ = ["demo"]


def demo(output_dir, seed: int = 0) -> dict:
    """Run the microstructure worked example into ``output_dir`` (about 20 s on 2 cores)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from scipy import ndimage

    from nmmm.microstructure.analysis import analyze_image
    from nmmm.microstructure.flakes import flake_deposit
    from nmmm.microstructure.hardcore import hardcore_particles
    from nmmm.microstructure.io import save_microstructure
    from nmmm.microstructure.rve import fit_rve

    out = Path(output_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    figures, tables = [], {}
    rng = np.random.default_rng(seed)

    # 1. hematite pseudo-cubes, 250 nm diagonal, 5 / 7 / 10 % (3-D cells, 20 nm voxels)
    box = (4000.0, 4000.0, 1000.0)
    vox = 10.0
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.6))
    cells = {}
    rows = []
    for ax, p in zip(axes, (0.05, 0.07, 0.10)):
        ps = hardcore_particles(box, "pseudocube", 250.0, p, exclusion_nm=20.0, exponent=8.0,
                                seed=int(rng.integers(1 << 30)), phase="hematite")
        m = ps.rasterize(vox)
        cells[p] = m
        sec = m.section(axis=2)
        ax.imshow(sec.labels.T, cmap="gray_r", extent=[0, box[0] / 1e3, box[1] / 1e3, 0])
        ax.set_title(f"hematite {p:.0%}: section (3-D fraction {m.volume_fraction():.3f})")
        ax.set_xlabel("x (µm)")
        ax.set_ylabel("y (µm)")
        rows.append({"target_fraction": p, "voxel_fraction_3d": m.volume_fraction(),
                     "section_fraction": sec.volume_fraction(), "n_particles": len(ps)})
    axes[0].set_ylabel("y (µm)")
    fig.tight_layout()
    f1 = out / "microstructure_hematite_sections.png"
    fig.savefig(f1, dpi=110)
    plt.close(fig)
    figures.append(str(f1))
    tables["hematite_cells"] = rows
    save_microstructure(cells[0.07], out / "microstructure_hematite_7pc.tif")

    # 2. SEM-like image of the 7 % section (blur + noise) and its analysis
    sec = cells[0.07].section(axis=2)
    img = ndimage.gaussian_filter(sec.labels.astype(float), 1.0) + rng.normal(0, 0.12, sec.shape)
    res = analyze_image(img, sec.voxel_nm, smooth_px=0.0, periodic=False)
    f2 = out / "microstructure_hematite_analysis.png"
    res.plot(f2, title="hematite 7 %: simulated SEM section, detected particles and exclusion zones")
    figures.append(str(f2))
    s = res.summary()
    tables["hematite_analysis"] = {
        "true_section_fraction": sec.volume_fraction(),
        "estimated_fraction": s["area_fraction"],
        "n_particles": s["n_particles"],
        "mean_equivalent_diameter_nm": s["mean_equivalent_diameter_nm"],
        "exclusion_radius_nm": s["exclusion_radius_nm"],
        "integral_range_nm2": s["integral_range_nm2"],
    }

    # 3. metallic paint: flake deposit in the seed's unit cell
    dep = flake_deposit(seed=int(rng.integers(1 << 30)))
    fm = dep.rasterize(voxel_nm=(1500.0, 1500.0, 100.0))
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    top = fm.labels.max(axis=2).T
    ax[0, 0].imshow(top, cmap="gray", extent=[0, 450, 450, 0])
    ax[0, 0].set_title(f"{len(dep)} aluminium flakes: top view (450 × 450 µm)")
    ax[0, 0].set(xlabel="x (µm)", ylabel="y (µm)")
    cut = fm.labels[:, fm.shape[1] // 2, :].T
    ax[0, 1].imshow(cut, cmap="gray", origin="lower", aspect="auto", extent=[0, 450, 0, 20])
    ax[0, 1].set_title("vertical cut (x, z), substrate at z = 0")
    ax[0, 1].set_xlabel("x (µm)")
    ax[0, 1].set_ylabel("z (µm)")
    ax[1, 0].hist(dep.tilt_deg, bins=30, color="tab:blue")
    ax[1, 0].set(xlabel="flake tilt (°)", ylabel="number of flakes (1)")
    ax[1, 1].hist(dep.depth_nm / 1e3, bins=30, color="tab:orange")
    ax[1, 1].set(xlabel="flake depth below the top surface (µm)", ylabel="number of flakes (1)")
    fig.tight_layout()
    f3 = out / "microstructure_flakes.png"
    fig.savefig(f3, dpi=110)
    plt.close(fig)
    figures.append(str(f3))
    tables["flakes"] = dep.summary() | {"voxel_fraction": fm.volume_fraction()}

    # 4. RVE of the hematite volume fraction (10 %), sub-volumes of 4 cells
    vals, vols = [], []
    big = [cells[0.10]] + [hardcore_particles(box, "pseudocube", 250.0, 0.10, exclusion_nm=20.0,
                                              seed=int(rng.integers(1 << 30))).rasterize(vox) for _ in range(2)]
    for L in (50, 100, 200):
        z = [c.labels[i:i + L, j:j + L, :].astype(bool).mean() for c in big
             for i in range(0, c.shape[0] - L + 1, L) for j in range(0, c.shape[1] - L + 1, L)]
        vals.append(np.array(z))
        vols.append(L * vox * L * vox * box[2])
    fit = fit_rve(vols, vals, point_variance=0.1 * 0.9, ndim=3)
    fig, ax = plt.subplots(figsize=(5.5, 4))
    v = np.array(vols)
    ax.loglog(v / 1e9, fit.variances, "o", label="realisations")
    ax.loglog(v / 1e9, fit.variance(v), "-", label=f"D²(V) = K V^-{fit.alpha:.2f}")
    ax.set_xlabel("domain volume (µm³)")
    ax.set_ylabel("variance of the volume fraction (1)")
    ax.legend()
    fig.tight_layout()
    f4 = out / "microstructure_rve.png"
    fig.savefig(f4, dpi=110)
    plt.close(fig)
    figures.append(str(f4))
    tables["rve_hematite_10pc"] = {
        "alpha": fit.alpha,
        "integral_range_um3": fit.integral_range / 1e9,
        "volume_1pc_1_realisation_um3": fit.volume_for(0.01, 1) / 1e9,
        "realisations_1pc_at_4um_cell": fit.realisations_for(0.01, float(np.prod(box))),
    }
    text = (
        "Hard-core pseudo-cubes of hematite (250 nm large diagonal, superball exponent 8, random "
        "orientations, 20 nm binder gap) at 5, 7 and 10 % volume; a simulated SEM section of the 7 % cell "
        "is analysed back (fraction, sizes, exclusion zones). A mixed Boolean/deposit layer of aluminium "
        "flakes fills the seed's 450 × 450 × 20 µm cell (kept as an analytic list, rasterised at "
        "1.5 × 1.5 × 0.1 µm). The RVE fit (Kanit et al. 2003) gives the cell size for 1 % precision on "
        f"the hematite fraction. Run time {time.perf_counter() - t0:.0f} s."
    )
    return {"title": "Microstructures: hematite pseudo-cubes and aluminium flakes", "figures": figures,
            "tables": tables, "text": text}
