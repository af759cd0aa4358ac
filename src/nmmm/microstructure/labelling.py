"""Binary images and their connected components, shared by the image analysis
(:mod:`nmmm.microstructure.analysis`) and the model estimators
(:mod:`nmmm.microstructure.estimation`), which both import it.

- :func:`label_particles` — connected components (1..n) of the particle phase, with
  optional periodic wrap (components continuing across opposite edges are merged).
- ``_as_image``, ``_as_binary`` — validation of the image arguments (a 2-D or 3-D array, or
  a :class:`~nmmm.microstructure.base.Microstructure`; binary = boolean or 0/1).

References
----------
- Serra, J. (1982). Image Analysis and Mathematical Morphology. Academic Press
  (connectivity, labelling of connected components).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage, sparse
from scipy.sparse import csgraph

from nmmm.errors import InvalidInputError
from nmmm.microstructure.base import Microstructure
from nmmm.spectra import check_finite

__all__ = ["label_particles"]


def _as_image(image, name="image") -> np.ndarray:
    if isinstance(image, Microstructure):
        return image.labels != 0
    a = np.asarray(image)
    if a.ndim not in (2, 3):
        raise InvalidInputError(f"{name} must be a 2-D (or 3-D) array, got shape {a.shape}")
    if a.dtype != bool:
        check_finite(a, name)
    return a


def _as_binary(binary) -> np.ndarray:
    a = _as_image(binary, "binary")
    if a.dtype != bool:
        u = np.unique(a)
        if u.size > 2 or not np.all(np.isin(u, (0, 1))):
            raise InvalidInputError(
                "expected a binary image (True/1 = particles); binarise grey levels first with binarize()"
            )
        a = a.astype(bool)
    return a


def label_particles(binary, periodic: bool = False, connectivity: int = 1):
    """Connected components (1..n) of the particle phase; ``periodic`` merges those that
    continue across opposite edges. Returns (labels, n)."""
    b = _as_binary(binary)
    struct = ndimage.generate_binary_structure(b.ndim, connectivity)
    lab, n = ndimage.label(b, structure=struct)
    if not periodic or n == 0:
        return lab, n
    pairs = []
    for ax in range(b.ndim):
        first = np.take(lab, 0, axis=ax)
        last = np.take(lab, -1, axis=ax)
        m = (first > 0) & (last > 0)
        pairs.append(np.stack([first[m], last[m]]))
    e = np.concatenate(pairs, axis=1)
    if e.shape[1] == 0:
        return lab, n
    g = sparse.coo_matrix((np.ones(e.shape[1]), (e[0], e[1])), shape=(n + 1, n + 1))
    _, comp = csgraph.connected_components(g, directed=False)
    # relabel 1..m in order, background stays 0
    keep = comp[1:]
    _, new = np.unique(keep, return_inverse=True)
    mapping = np.concatenate([[0], new + 1])
    lab = mapping[lab]
    return lab, int(new.max() + 1)
