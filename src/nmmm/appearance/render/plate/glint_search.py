"""The glint search over the visible tiles of the flake unit cell (Numba): for each tile and
light, the flakes whose normals lie near the tile's half vector (a grid on the normals)
are tested for a mirror path light → flake → camera through the coat, and each glint is
recorded with its pixel(s) — point splat, or area splat over its footprint
(:mod:`~nmmm.appearance.render.plate.footprint`) — its weight and its angles. Tiles get a
deterministic pseudo-random shift, rotation and tilt variant (``_tile_hash``, splitmix64).

References
----------
- W. Jakob, M. Hašan, L.-Q. Yan, J. Lawrence, R. Ramamoorthi, S. Marschner, "Discrete
  stochastic microfacet models", ACM TOG 33(4) (2014) — glints as discrete facets
  integrated over a pixel footprint and a light's solid angle.
"""

from __future__ import annotations

import math

import numpy as np

from nmmm.appearance.render.plate.footprint import _ellipse_coverage
from nmmm.errors import InvalidInputError

try:  # pragma: no cover - numba is a dependency, but keep a NumPy path
    import numba as _nb
except ImportError:  # pragma: no cover
    _nb = None


def _glint_tiles_py(*args):  # pragma: no cover - only without numba
    raise InvalidInputError("discrete flakes (glints) need numba")


if _nb is not None:
    @_nb.njit(cache=True, fastmath=True)
    def _lerp1_nb(tab, th, step):
        x = th / step
        if x < 0:
            x = 0.0
        i0 = int(x)
        if i0 >= tab.shape[0] - 1:
            return tab[tab.shape[0] - 1]
        f = x - i0
        return tab[i0] * (1 - f) + tab[i0 + 1] * f

    @_nb.njit(cache=True)
    def _tile_hash(i, j, seed):
        """Deterministic pseudo-random numbers in [0, 1) for tile (i, j) (splitmix64)."""
        z = (np.uint64(i) * np.uint64(0x9E3779B97F4A7C15)) ^ (np.uint64(j) * np.uint64(0xC2B2AE3D27D4EB4F)) \
            ^ np.uint64(seed)
        out = np.empty(4)
        for k in range(4):
            z = z + np.uint64(0x9E3779B97F4A7C15)
            x = z
            x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
            x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
            x = x ^ (x >> np.uint64(31))
            out[k] = float(x >> np.uint64(11)) / 9007199254740992.0
        return out

    @_nb.njit(parallel=True, cache=True, fastmath=True)
    def _glint_tiles(fill, offsets, rec_pix, rec_w, rec_th, rec_li, counts,
                     cam, cam_r, cam_u, cam_f, tx, ty, sx, sy, W, H,
                     hx, hy, cw, ch, i0, i1, j0, j1,
                     fpos, fnrm, farea, fdiam, fzeta, fpig, G, gstart_all, gorder_all,
                     lkind, lvec, lscale, n, sigma, cut, a_tab, astep, randomize, seed, splat,
                     alpha=0.0, rcut=0.0):
        """One pass over the visible tiles (rows j in parallel): count (fill=False) or
        write (fill=True) the glint records (pixel, weight, angles, light). ``fpig`` (N,) is
        the fraction of the coat's pigment optical thickness κ above each flake (z0 + dz ζ),
        recorded as S' fpig (S' = 1/μi' + 1/μo') for the pigments' exp(−κ S' fpig). ``rec_th``
        with 9 columns (flakes that transmit): also θi', θo' (degrees) and ζ/μi', ζ/μo', for the
        flake layer's extinction per direction (``_Tables.ext_tab``) in the splat.

        ``alpha`` > 0: rough flake faces (GGX α, :meth:`~nmmm.appearance.flakes.TiltDistribution.
        roughened`'s law). A flake then reflects through the facet normal h' of the actual
        light → flake → camera path (not its mirror direction): its facets have the density
        D(δ) cos δ per sr at the tilt-vector offset δ = t(h') − t(m) (small-angle composition,
        with the per-tilt-area Jacobians sin δ/δ and θh/sin θh of the FFT composition), D of
        roughness α_eff, α_eff² = α² + 2 σ_n², σ_n² = σ_g² J the source's lobe moved to the
        normals (J = dω_h/dω_o = cos θo / (4 n² (ωi'·h') cos θo')), cut at δ <= ``rcut``; the
        lobe per external sr is that density times J, the reflectance is taken at ωi'·h'."""
        pix_sa = (2 * tx / W) * (2 * ty / H)
        ext_cols = rec_th.shape[1] > 5
        nl = lkind.size
        inv2s2 = 1.0 / (2 * sigma * sigma)
        gnorm = 1.0 / (2 * math.pi * sigma * sigma * (1 - math.exp(-0.5 * cut * cut)))
        maxang = cut * sigma
        cosmax = math.cos(maxang)
        half_diag = 0.5 * math.sqrt(cw * cw + ch * ch)
        # a flake normal m off the half vector h' by δ sends the external mirror ray at
        # least 2 n cos θd' δ >= 2 sqrt(n² - 1) δ away (reflection + Snell, θd' below the
        # critical angle): search normals within maxang / (2 sqrt(n² - 1)), +10 %
        mfac = min(2.0, 1.1 / (2 * math.sqrt(max(n * n - 1, 1e-6))))
        for jj in _nb.prange(j1 - j0):
            j = j0 + jj
            cnt = 0
            base = offsets[jj]
            for i in range(i0, i1):
                ox = -hx + i * cw
                oy = -hy + j * ch
                if randomize:
                    rnd = _tile_hash(i, j, seed)
                    cph = math.cos(2 * math.pi * rnd[0])
                    sph = math.sin(2 * math.pi * rnd[0])
                    offx = rnd[1] * cw
                    offy = rnd[2] * ch
                    var = min(int(rnd[3] * fnrm.shape[0]), fnrm.shape[0] - 1)
                else:
                    cph, sph, offx, offy = 1.0, 0.0, 0.0, 0.0
                    var = 0
                gstart = gstart_all[var]
                gorder = gorder_all[var]
                pcx = ox + 0.5 * cw
                pcy = oy + 0.5 * ch
                # camera direction at the tile centre
                vx = cam[0] - pcx
                vy = cam[1] - pcy
                vz = cam[2]
                dc = math.sqrt(vx * vx + vy * vy + vz * vz)
                vx /= dc
                vy /= dc
                vz /= dc
                # internal outgoing direction
                ox_ = vx / n
                oy_ = vy / n
                oz_ = math.sqrt(max(0.0, 1 - ox_ * ox_ - oy_ * oy_))
                for li in range(nl):
                    if lkind[li] == 0:
                        wx, wy, wz = lvec[li, 0], lvec[li, 1], lvec[li, 2]
                        dl = 1e30
                    else:
                        wx = lvec[li, 0] - pcx
                        wy = lvec[li, 1] - pcy
                        wz = lvec[li, 2]
                        dl = math.sqrt(wx * wx + wy * wy + wz * wz)
                        wx /= dl
                        wy /= dl
                        wz /= dl
                    if wz <= 0:
                        continue
                    ix = wx / n
                    iy = wy / n
                    iz = math.sqrt(max(0.0, 1 - ix * ix - iy * iy))
                    hxv = ix + ox_
                    hyv = iy + oy_
                    hzv = iz + oz_
                    hn = math.sqrt(hxv * hxv + hyv * hyv + hzv * hzv)
                    hxv /= hn
                    hyv /= hn
                    # to the unit cell's frame (normals rotated by phi in this tile)
                    hxc = cph * hxv + sph * hyv
                    hyc = -sph * hxv + cph * hyv
                    hxv = hxc
                    hyv = hyc
                    # search radius in the flake-normal (m_x, m_y) plane
                    r = max(mfac * maxang, 1.1 * rcut) + half_diag / dc + half_diag / dl
                    bx0 = int(math.floor((hxv - r + 1) * 0.5 * G))
                    bx1 = int(math.floor((hxv + r + 1) * 0.5 * G))
                    by0 = int(math.floor((hyv - r + 1) * 0.5 * G))
                    by1 = int(math.floor((hyv + r + 1) * 0.5 * G))
                    bx0 = max(bx0, 0)
                    by0 = max(by0, 0)
                    bx1 = min(bx1, G - 1)
                    by1 = min(by1, G - 1)
                    for by in range(by0, by1 + 1):
                        for bx in range(bx0, bx1 + 1):
                            b = by * G + bx
                            for q in range(gstart[b], gstart[b + 1]):
                                k = gorder[q]
                                px = ox + (fpos[k, 0] + offx) % cw
                                py = oy + (fpos[k, 1] + offy) % ch
                                if px < -hx or px > hx or py < -hy or py > hy:
                                    continue
                                dx = px - cam[0]
                                dy = py - cam[1]
                                dz = -cam[2]
                                d = math.sqrt(dx * dx + dy * dy + dz * dz)
                                wox = -dx / d
                                woy = -dy / d
                                woz = -dz / d
                                # light direction and plane irradiance factor at the flake
                                if lkind[li] == 0:
                                    lx, ly, lz = wx, wy, wz
                                    e = lscale[li] * lz
                                else:
                                    lx = lvec[li, 0] - px
                                    ly = lvec[li, 1] - py
                                    lz = lvec[li, 2]
                                    r2 = lx * lx + ly * ly + lz * lz
                                    rl = math.sqrt(r2)
                                    lx /= rl
                                    ly /= rl
                                    lz /= rl
                                    if lz <= 0:
                                        continue
                                    e = lscale[li] / (r2 * 1e-6) * lz
                                jx = lx / n
                                jy = ly / n
                                jz = math.sqrt(max(0.0, 1 - jx * jx - jy * jy))
                                mx = cph * fnrm[var, k, 0] - sph * fnrm[var, k, 1]
                                my = sph * fnrm[var, k, 0] + cph * fnrm[var, k, 1]
                                mz = fnrm[var, k, 2]
                                ca = 1.0
                                if alpha > 0.0:
                                    # rough faces: the facet normal of the actual path
                                    if woz <= 0:
                                        continue
                                    qx = wox / n
                                    qy = woy / n
                                    qz = math.sqrt(max(0.0, 1 - qx * qx - qy * qy))
                                    fz = woz
                                    h1 = jx + qx
                                    h2 = jy + qy
                                    h3 = jz + qz
                                    hl = math.sqrt(h1 * h1 + h2 * h2 + h3 * h3)
                                    h1 /= hl
                                    h2 /= hl
                                    h3 /= hl
                                    c = h1 * jx + h2 * jy + h3 * jz
                                    if c <= 0 or qz <= 0:
                                        continue
                                    sh = math.sqrt(h1 * h1 + h2 * h2)
                                    th_h = math.atan2(sh, h3)
                                    fh = th_h / sh if sh > 1e-12 else 1.0
                                    sm = math.sqrt(mx * mx + my * my)
                                    fm = math.atan2(sm, mz) / sm if sm > 1e-12 else 1.0
                                    ddx = fh * h1 - fm * mx
                                    ddy = fh * h2 - fm * my
                                    dlt = math.sqrt(ddx * ddx + ddy * ddy)
                                    if dlt > rcut:
                                        continue
                                    jac = woz / (4 * n * n * c * qz)
                                    ae2 = alpha * alpha + 2 * sigma * sigma * jac
                                    cd = math.cos(dlt)
                                    dd = cd * cd * (ae2 - 1.0) + 1.0
                                    kf = ae2 / (math.pi * dd * dd) * cd
                                    if dlt > 1e-12:
                                        kf *= math.sin(dlt) / dlt
                                    if sh > 1e-12:
                                        kf *= th_h / sh
                                    grough = kf * jac
                                else:
                                    c = mx * jx + my * jy + mz * jz
                                    if c <= 0:
                                        continue
                                    qx = 2 * c * mx - jx
                                    qy = 2 * c * my - jy
                                    qz = 2 * c * mz - jz
                                    s2 = n * n * (qx * qx + qy * qy)
                                    if qz <= 0 or s2 >= 1:
                                        continue
                                    fx = n * qx
                                    fy = n * qy
                                    fz = math.sqrt(1 - s2)
                                    ca = fx * wox + fy * woy + fz * woz
                                    if ca < cosmax:
                                        continue
                                    grough = 0.0
                                zc = dx * cam_f[0] + dy * cam_f[1] + dz * cam_f[2]
                                if zc <= 0:
                                    continue
                                uc = (dx * cam_r[0] + dy * cam_r[1] + dz * cam_r[2]) / zc
                                vc = (dx * cam_u[0] + dy * cam_u[1] + dz * cam_u[2]) / zc
                                u = uc / tx - sx
                                v = vc / ty - sy
                                colf = (u + 1) * 0.5 * W
                                rowf = (1 - v) * 0.5 * H
                                # projected footprint of the flake disc (radius rho, normal m):
                                # affine (Jacobian) image of the disc at its centre, an ellipse
                                # c + s A1 + t A2 (s² + t² <= 1) in pixel units
                                rho = 0.5 * fdiam[k]
                                if abs(mx) <= abs(my):
                                    e1x, e1y, e1z = 0.0, -mz, my  # x̂ × m (unnormalised, |.| >= 1/√2)
                                else:
                                    e1x, e1y, e1z = mz, 0.0, -mx  # ŷ × m
                                en = math.sqrt(e1x * e1x + e1y * e1y + e1z * e1z)
                                e1x /= en
                                e1y /= en
                                e1z /= en
                                e2x = my * e1z - mz * e1y
                                e2y = mz * e1x - mx * e1z
                                e2z = mx * e1y - my * e1x
                                # d(col)/dX = W/2 (r - uc f) / (zc tx); d(row)/dX = -H/2 (up - vc f) / (zc ty)
                                kc = rho * 0.5 * W / (zc * tx)
                                kr = -rho * 0.5 * H / (zc * ty)
                                a1x = kc * ((cam_r[0] - uc * cam_f[0]) * e1x + (cam_r[1] - uc * cam_f[1]) * e1y
                                            + (cam_r[2] - uc * cam_f[2]) * e1z)
                                a2x = kc * ((cam_r[0] - uc * cam_f[0]) * e2x + (cam_r[1] - uc * cam_f[1]) * e2y
                                            + (cam_r[2] - uc * cam_f[2]) * e2z)
                                a1y = kr * ((cam_u[0] - vc * cam_f[0]) * e1x + (cam_u[1] - vc * cam_f[1]) * e1y
                                            + (cam_u[2] - vc * cam_f[2]) * e1z)
                                a2y = kr * ((cam_u[0] - vc * cam_f[0]) * e2x + (cam_u[1] - vc * cam_f[1]) * e2y
                                            + (cam_u[2] - vc * cam_f[2]) * e2z)
                                ex = math.sqrt(a1x * a1x + a2x * a2x)  # bounding-box half sizes
                                ey = math.sqrt(a1y * a1y + a2y * a2y)
                                det = a1x * a2y - a2x * a1y
                                area = splat and max(ex, ey) > 0.5 and abs(det) > 1e-12
                                col = int(math.floor(colf))
                                row = int(math.floor(rowf))
                                if area:
                                    c0 = max(int(math.floor(colf - ex)), 0)
                                    c1 = min(int(math.floor(colf + ex)), W - 1)
                                    r0 = max(int(math.floor(rowf - ey)), 0)
                                    r1 = min(int(math.floor(rowf + ey)), H - 1)
                                    if c0 > c1 or r0 > r1:
                                        continue
                                elif col < 0 or col >= W or row < 0 or row >= H:
                                    continue
                                if alpha > 0.0:
                                    g = grough
                                else:
                                    ang = math.acos(min(1.0, ca))
                                    g = gnorm * math.exp(-ang * ang * inv2s2)
                                cosa = zc / d
                                omega = pix_sa * cosa * cosa * cosa
                                wgt = e * farea[k] * c / jz * g / (omega * d * d)
                                th0 = 0.0
                                th1 = 0.0
                                th2 = 0.0
                                th3 = 0.0
                                th4 = 0.0
                                th5 = 0.0
                                th6 = 0.0
                                th7 = 0.0
                                th8 = 0.0
                                if fill:
                                    th0 = math.degrees(math.acos(min(1.0, lz)))
                                    th1 = math.degrees(math.acos(min(1.0, fz)))
                                    th2 = math.degrees(math.acos(min(1.0, c)))
                                    S = (_lerp1_nb(a_tab, math.degrees(math.acos(min(1.0, jz))), astep) / jz
                                         + _lerp1_nb(a_tab, math.degrees(math.acos(min(1.0, qz))), astep) / qz)
                                    th3 = S * fzeta[k]
                                    th4 = (1.0 / jz + 1.0 / qz) * fpig[k]
                                    if ext_cols:  # flakes that transmit: the internal angles, ζ/μi', ζ/μo'
                                        th5 = math.degrees(math.acos(min(1.0, jz)))
                                        th6 = math.degrees(math.acos(min(1.0, qz)))
                                        th7 = fzeta[k] / jz
                                        th8 = fzeta[k] / qz
                                if not area:
                                    if fill:
                                        o = base + cnt
                                        rec_pix[o] = row * W + col
                                        rec_w[o] = wgt
                                        rec_th[o, 0] = th0
                                        rec_th[o, 1] = th1
                                        rec_th[o, 2] = th2
                                        rec_th[o, 3] = th3
                                        rec_th[o, 4] = th4
                                        if ext_cols:
                                            rec_th[o, 5] = th5
                                            rec_th[o, 6] = th6
                                            rec_th[o, 7] = th7
                                            rec_th[o, 8] = th8
                                        rec_li[o] = li
                                    cnt += 1
                                    continue
                                # area splat: the flake's power wgt·Ω(flake) shared over the pixels
                                # in proportion to their covered area (the whole ellipse, frame
                                # included or not), each divided by its own solid angle Ω_p
                                idet = 1.0 / det
                                tot = 0.0
                                first = base + cnt
                                for rr in range(int(math.floor(rowf - ey)), int(math.floor(rowf + ey)) + 1):
                                    for cc in range(int(math.floor(colf - ex)), int(math.floor(colf + ex)) + 1):
                                        cov = _ellipse_coverage(cc - colf, rr - rowf, a1x, a1y, a2x, a2y, idet)
                                        if cov <= 0.0:
                                            continue
                                        tot += cov
                                        if cc < c0 or cc > c1 or rr < r0 or rr > r1:
                                            continue
                                        if fill:
                                            o = base + cnt
                                            up_ = (2 * (cc + 0.5) / W - 1 + sx) * tx
                                            vp_ = (1 - 2 * (rr + 0.5) / H + sy) * ty
                                            cp = 1.0 / math.sqrt(1 + up_ * up_ + vp_ * vp_)
                                            rec_pix[o] = rr * W + cc
                                            rec_w[o] = wgt * cov * omega / (pix_sa * cp * cp * cp)
                                            rec_th[o, 0] = th0
                                            rec_th[o, 1] = th1
                                            rec_th[o, 2] = th2
                                            rec_th[o, 3] = th3
                                            rec_th[o, 4] = th4
                                            if ext_cols:
                                                rec_th[o, 5] = th5
                                                rec_th[o, 6] = th6
                                                rec_th[o, 7] = th7
                                                rec_th[o, 8] = th8
                                            rec_li[o] = li
                                        cnt += 1
                                if fill and tot > 0.0:
                                    for o in range(first, base + cnt):
                                        rec_w[o] /= tot
            counts[jj] = cnt
else:  # pragma: no cover
    _glint_tiles = _glint_tiles_py
