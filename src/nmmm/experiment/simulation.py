"""Simulated inputs for the 2AFC experiment: synthetic image pairs and simulated observers.

- :func:`synthetic_pairs` — write small synthetic 'rendered' and 'photo' images and a
  ``pairs.toml`` for them (to try ``nmmm experiment serve`` without a real plate).
- :func:`simulate_responses` — fill a response database with simulated observers whose
  probability of picking the photograph varies from observer to observer (beta distribution).

The simulated observers are not data: they show what the analysis reports for a rendering
that is nearly, but not perfectly, indistinguishable from the photograph (tests, benchmarks and
``nmmm demo`` use them).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nmmm.experiment.pairs import make_pairs_file

__all__ = ["synthetic_pairs", "simulate_responses"]


def synthetic_pairs(output_dir, n_pairs: int = 10, size_px: int = 96, seed: int = 0, **settings) -> Path:
    """Write ``n_pairs`` synthetic image pairs and ``pairs.toml`` into ``output_dir``; return its path.

    Each 'photo' is a smooth colour gradient with a little grain; the 'rendered' image is the
    same gradient with slightly less grain (stand-ins for a real photograph and rendering).
    """
    from PIL import Image

    out = Path(output_dir)
    img_dir = out / "images"
    img_dir.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size_px, 0:size_px] / size_px
    triples = []
    for i in range(n_pairs):
        base = rng.uniform(0.25, 0.75, 3)
        tilt = rng.uniform(-0.2, 0.2, 3)
        smooth = np.clip(base[None, None, :] + tilt[None, None, :] * (x + y)[..., None] / 2, 0, 1)
        photo = np.clip(smooth + rng.normal(0, 0.03, smooth.shape), 0, 1)
        render = np.clip(smooth + rng.normal(0, 0.02, smooth.shape), 0, 1)
        p_photo = img_dir / f"plate{i + 1:02d}_photo.png"
        p_render = img_dir / f"plate{i + 1:02d}_render.png"
        Image.fromarray((photo * 255).round().astype(np.uint8)).save(p_photo)
        Image.fromarray((render * 255).round().astype(np.uint8)).save(p_render)
        triples.append((p_render, p_photo, f"plate {i + 1:02d}"))
    return make_pairs_file(triples, out / "pairs.toml", **settings)


def simulate_responses(pairset, db_path, *, n_observers: int = 40, mean_pc: float = 0.55, rho: float = 0.05,
                       median_rt_ms: float = 1400.0, seed: int = 0) -> Path:
    """Fill ``db_path`` with simulated observers of the experiment ``pairset``.

    Observer ``i`` picks the photograph with probability ``p_i ~ Beta(mean_pc, rho)`` (mean
    ``mean_pc``, intra-class correlation ``rho``); response times are log-normal around
    ``median_rt_ms``. Participants, trials and responses go through
    :class:`~nmmm.experiment.storage.ResponseStore`, exactly as the web server stores them.
    """
    import uuid

    from nmmm.experiment.storage import ResponseStore

    rng = np.random.default_rng(seed)
    a = mean_pc * (1 - rho) / rho
    b = (1 - mean_pc) * (1 - rho) / rho
    with ResponseStore(db_path, synchronous="OFF") as store:
        store.register_pairs(pairset)
        for i in range(n_observers):
            part = store.create_participant(f"S{i + 1:02d}", pairset, consent_sha256="simulated",
                                            user_agent="simulation", seed=int(rng.integers(2**62)))
            p_i = rng.beta(a, b)
            pid = part["participant_id"]
            for t in range(part["n_trials"]):
                trial = store.trial(pid, t)
                correct = rng.random() < p_i
                chosen = trial["photo_slot"] if correct else 1 - trial["photo_slot"]
                rt = float(median_rt_ms * np.exp(rng.normal(0, 0.35)))
                store.record_response(pid, t, str(uuid.UUID(bytes=rng.bytes(16), version=4)), chosen, rt)
    return Path(db_path)
