"""The footprint of a flake on the image: the projected flake disc is an ellipse
c + s A1 + t A2 (s² + t² <= 1) in pixel units, and ``_ellipse_coverage`` gives the
fraction of a pixel it covers (exact for pixels inside it, an 8 × 8 sub-pixel count on its
boundary), for the area splatting of glints wider than a pixel.
"""

from __future__ import annotations

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None

_SUPERSAMPLE = 8  # sub-pixel grid (per axis) of the glint footprint coverage on boundary pixels

if _nb is not None:
    @_nb.njit(cache=True, fastmath=True)
    def _ellipse_coverage(x0, y0, a1x, a1y, a2x, a2y, idet):
        """Fraction of the unit pixel [x0, x0 + 1] × [y0, y0 + 1] (relative to the ellipse
        centre) inside the ellipse {s A1 + t A2 : s² + t² <= 1}: 1 when its four corners are
        inside (the ellipse is convex), else the fraction of an 8 × 8 grid of sub-pixel
        centres inside (error <= 1/64 of a pixel per boundary pixel, unbiased on average)."""
        inside = 0
        for cy in range(2):
            for cx in range(2):
                x = x0 + cx
                y = y0 + cy
                s = (a2y * x - a2x * y) * idet
                t = (-a1y * x + a1x * y) * idet
                if s * s + t * t <= 1.0:
                    inside += 1
        if inside == 4:
            return 1.0
        ns = _SUPERSAMPLE
        cnt = 0
        for iy in range(ns):
            y = y0 + (iy + 0.5) / ns
            for ix in range(ns):
                x = x0 + (ix + 0.5) / ns
                s = (a2y * x - a2x * y) * idet
                t = (-a1y * x + a1x * y) * idet
                if s * s + t * t <= 1.0:
                    cnt += 1
        return cnt / (ns * ns)
else:  # pragma: no cover
    _ellipse_coverage = None  # only used by the Numba glint search
