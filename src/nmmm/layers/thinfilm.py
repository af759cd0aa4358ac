"""Thin-film optics of layer stacks by 2×2 transfer (characteristic) matrices.

A :class:`Stack` is a semi-infinite ambient, a list of layers and a semi-infinite
substrate. Each layer is coherent (interference inside it: thin films, oxide layers on
mica) or incoherent (thick clear coats, glass sheets: intensities add, phases average
out). :meth:`Stack.rt` returns s, p and unpolarized reflectance and transmittance — and,
for a fully coherent stack, the complex amplitude coefficients ``rs, rp, ts, tp`` that
ellipsometry needs — vectorised over wavelength × angle × thickness grids in one call.

Public objects
--------------
- :class:`Layer` — a material (or constant ``n + ik``), a thickness in nm, coherent or not.
- :class:`Stack` — ambient, layers, substrate; :meth:`Stack.rt`.
- :class:`StackResult` — ``Rs, Rp, Ts, Tp, R, T, A`` (power), ``rs, rp, ts, tp``
  (complex, coherent stacks only), absorption per layer on request.
- :func:`coherent_rt` — the batched kernel on plain arrays (indices, thicknesses).

Method
------
Coherent part: the characteristic matrix of each layer (Born & Wolf §1.6.2; Macleod 2010
§2.2), ``[[cos δ, −i sin δ/η], [−i η sin δ, cos δ]]`` with ``δ = 2π n cos θ d/λ`` and
tilted admittance ``η = n cos θ`` (s) or ``n/cos θ`` (p) — written here for ``n + ik`` and
``exp(−iωt)``, the complex conjugate of Macleod's form. Each matrix is multiplied by
``exp(iδ)`` so that its entries stay bounded (``|exp(2iδ)| <= 1`` since
``Im(n cos θ) >= 0``) even for thick absorbing layers; the factors are restored exactly in
``t``. The products are applied to the vector ``[B, C]`` from the substrate upwards, as
batched complex arithmetic over every wavelength, angle and thickness at once.
``r = (η0 B − C)/(η0 B + C)``; ``rp`` is negated to follow the convention of
:mod:`nmmm.layers.fresnel_equations` (``rp = −rs`` at normal incidence, as in the ``tmm`` package
and Fujiwara 2007), and ``tp`` is converted from tangential to full field amplitudes.
``T = |t_tan|² Re(η_sub)/Re(η0)``, the transmitted Poynting flux into the substrate.

Incoherent layers: the coherent groups between incoherent media are reduced to their
power ``R, T`` from both sides and combined with the single-pass intensity attenuation
``P = exp(−4π Im(n cos θ) d/λ)`` of each incoherent layer by the adding (power
transfer matrix) recurrence of Katsidis & Siapkas (2002) and Byrnes (2016, §5). The
ambient and the substrate are semi-infinite, hence incoherent.

Absorption per layer is the difference of the net Poynting flux at its two faces; for
coherent layers inside an incoherent stack, the sum of the absorption driven from above
and from below (mutually incoherent).

Caveats: an absorbing ambient is accepted; ``R`` and ``T`` are then normalised to the
Poynting flux of the incident wave alone (as in ``tmm``), and the same holds for the
power exchanged through absorbing incoherent layers — ``R + T + A = 1`` holds exactly for
non-absorbing ambients. Layers are isotropic; roughness is not modelled.

References
----------
- M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge University Press (1999),
  §1.6. doi:10.1017/CBO9781139644181
- H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press (2010), ch. 2.
- S. J. Byrnes, "Multilayer optical calculations", arXiv:1603.02720 (2016).
- C. C. Katsidis, D. I. Siapkas, "General transfer-matrix method for optical multilayer
  systems with coherent, partially coherent, and incoherent interference",
  Appl. Opt. 41, 3978 (2002). doi:10.1364/AO.41.003978
- H. Fujiwara, *Spectroscopic Ellipsometry*, Wiley (2007), §2.3.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from typing import Any, Sequence

import numba

import numpy as np

from nmmm.errors import InvalidInputError
from nmmm.layers.fresnel_equations import UnpolarizedPower, check_angle_deg, medium_nk, n_cos_theta
from nmmm.spectra import as_wavelength_nm, check_finite, check_nk, check_positive

__all__ = ["Layer", "Stack", "StackResult", "coherent_rt", "NUMBA_MIN_POINTS"]

#: result size (points) from which ``Stack.rt(method="auto")`` uses the Numba kernel
NUMBA_MIN_POINTS = 2048


# ----------------------------------------------------------------------------------------
# optical constants of a layer: a Material or a constant / per-wavelength n + ik
# ----------------------------------------------------------------------------------------
def _check_medium(value, what: str):
    """Accept an object with ``.nk(wavelength_nm)`` (a nmmm Material) or complex n + ik."""
    if hasattr(value, "nk") and callable(value.nk):
        return value
    if isinstance(value, (str, bytes)):
        raise InvalidInputError(
            f"{what}: got the string {value!r}; pass a Material (e.g. nmmm.materials.get({value!r})) "
            "or a complex refractive index n + ik"
        )
    try:
        nk = check_nk(value, what)
    except InvalidInputError:
        raise
    except (TypeError, ValueError) as exc:  # pragma: no cover - defensive
        raise InvalidInputError(f"{what}: expected a Material or complex n + ik, got {value!r}") from exc
    if np.any(nk == 0):
        raise InvalidInputError(f"{what}: refractive index 0 is not a medium")
    if np.any(nk.real < 0):
        raise InvalidInputError(f"{what}: Re(n) < 0 ({nk.real.min():g}); give n + ik with n > 0, k >= 0")
    return nk


def _medium_name(value) -> str:
    if hasattr(value, "nk"):
        return getattr(value, "name", type(value).__name__)
    v = np.asarray(value)
    if v.ndim == 0:
        return f"n={complex(v):g}"
    return f"n[{v.size}]"


def _eval_nk(value, w_nm: np.ndarray, what: str) -> np.ndarray:
    """n + ik of a medium on the wavelength array ``w_nm`` (same shape)."""
    if hasattr(value, "nk"):
        return medium_nk(value, w_nm, what)
    nk = np.asarray(value, dtype=complex)
    if nk.ndim == 0:
        return np.broadcast_to(nk, w_nm.shape)
    try:
        return np.broadcast_to(nk, w_nm.shape)
    except ValueError:
        raise InvalidInputError(
            f"{what}: an n + ik array of shape {nk.shape} must match the wavelength array "
            f"of shape {w_nm.shape}"
        ) from None


# ----------------------------------------------------------------------------------------
# objects
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Layer:
    """One layer of a :class:`Stack`.

    Parameters
    ----------
    material : Material or complex
        A nmmm :class:`~nmmm.materials.material.Material` (anything with
        ``.nk(wavelength_nm)``), a constant ``n + ik``, or an array of ``n + ik`` with the
        shape of the wavelength array later given to :meth:`Stack.rt`.
    thickness_nm : float or ndarray
        Thickness in nm, > 0. An array gives a thickness grid: results gain its
        dimensions in front of the wavelength and angle axes (thickness arrays of several
        layers broadcast together by NumPy rules).
    coherent : bool
        ``True`` (default) for interference in the layer; ``False`` for a thick layer
        whose internal reflections add in intensity (clear coat, glass).
    """

    material: Any
    thickness_nm: Any
    coherent: bool = True

    def __post_init__(self):
        object.__setattr__(self, "material", _check_medium(self.material, "layer material"))
        d = check_positive(self.thickness_nm, "thickness_nm")
        object.__setattr__(self, "thickness_nm", d)
        c = self.coherent
        if isinstance(c, str):
            if c not in ("c", "i"):
                raise InvalidInputError(f"coherent flag must be True/False or 'c'/'i' (tmm convention), got {c!r}")
            c = c == "c"
        if not isinstance(c, (bool, np.bool_)):
            raise InvalidInputError(f"coherent must be a bool, got {c!r}")
        object.__setattr__(self, "coherent", bool(c))

    @property
    def name(self) -> str:
        return _medium_name(self.material)

    def __repr__(self) -> str:
        d = self.thickness_nm
        ds = f"{float(d):g} nm" if d.ndim == 0 else f"{d.size} thicknesses {d.min():g}–{d.max():g} nm"
        return f"Layer({self.name}, {ds}{'' if self.coherent else ', incoherent'})"


def _as_layer(spec) -> Layer:
    if isinstance(spec, Layer):
        return spec
    if isinstance(spec, (tuple, list)) and len(spec) in (2, 3):
        return Layer(*spec)
    raise InvalidInputError(
        f"a layer is a Layer or a tuple (material_or_nk, thickness_nm[, coherent]); got {spec!r}"
    )


@dataclass(frozen=True)
class StackResult(UnpolarizedPower):
    """Reflection and transmission of a :class:`Stack`.

    Every array has shape ``thickness_shape + grid_shape`` (see :meth:`Stack.rt`).

    Attributes
    ----------
    wavelength_nm, angle_deg : ndarray
        The inputs, as given.
    Rs, Rp, Ts, Tp : ndarray
        Power reflectance and transmittance (into the substrate), s and p.
    rs, rp, ts, tp : complex ndarray or None
        Amplitude coefficients (conventions of :mod:`nmmm.layers.fresnel_equations`; ``ts, tp``
        full-field ratios substrate/incident); ``None`` when the stack has incoherent
        layers, for which no phase is defined.
    absorbed_s, absorbed_p : ndarray or None
        Fraction of the incident power absorbed in each layer, shape
        ``(n_layers,) + shape``; filled when ``rt(..., layer_absorption=True)``.
    """

    wavelength_nm: np.ndarray
    angle_deg: np.ndarray
    Rs: np.ndarray
    Rp: np.ndarray
    Ts: np.ndarray
    Tp: np.ndarray
    rs: np.ndarray | None = None
    rp: np.ndarray | None = None
    ts: np.ndarray | None = None
    tp: np.ndarray | None = None
    absorbed_s: np.ndarray | None = field(default=None, repr=False)
    absorbed_p: np.ndarray | None = field(default=None, repr=False)

    @property
    def As(self) -> np.ndarray:
        """Total absorptance of the layers, s: ``1 − Rs − Ts``."""
        return 1.0 - self.Rs - self.Ts

    @property
    def Ap(self) -> np.ndarray:
        """Total absorptance of the layers, p: ``1 − Rp − Tp``."""
        return 1.0 - self.Rp - self.Tp

    @property
    def A(self) -> np.ndarray:
        """Unpolarized total absorptance ``1 − R − T``."""
        return 1.0 - self.R - self.T

    @property
    def absorbed(self) -> np.ndarray | None:
        """Unpolarized absorption per layer, ``(absorbed_s + absorbed_p)/2``."""
        if self.absorbed_s is None:
            return None
        return 0.5 * (self.absorbed_s + self.absorbed_p)


@dataclass(frozen=True, eq=False)
class Stack:
    """A planar multilayer: ambient | layers (top to bottom) | substrate.

    Parameters
    ----------
    layers : sequence
        Each a :class:`Layer` or a tuple ``(material_or_nk, thickness_nm)`` or
        ``(material_or_nk, thickness_nm, coherent)`` where ``coherent`` is a bool or
        the ``tmm`` letters ``'c'`` / ``'i'``. Light enters from the ambient through
        ``layers[0]`` first. May be empty (a single interface).
    ambient : Material or complex
        Semi-infinite incidence medium (default air, 1.0).
    substrate : Material or complex
        Semi-infinite exit medium. A substrate whose back side matters (a glass sheet
        in air) is an incoherent layer over an air substrate.

    Examples
    --------
    A quarter-wave MgF2 layer (n = 1.38) on glass (n = 1.52) at 550 nm: the reflectance
    is ``((n0 ns − n1²)/(n0 ns + n1²))²`` (Macleod 2010 §3.2):

    >>> s = Stack([(1.38, 550 / (4 * 1.38))], ambient=1.0, substrate=1.52)
    >>> round(float(s.rt(550.0).R), 6), round(((1.52 - 1.38**2) / (1.52 + 1.38**2)) ** 2, 6)
    (0.012601, 0.012601)
    """

    layers: Sequence = ()
    ambient: Any = 1.0
    substrate: Any = 1.0

    def __post_init__(self):
        layers = tuple(_as_layer(s) for s in self.layers)
        object.__setattr__(self, "layers", layers)
        object.__setattr__(self, "ambient", _check_medium(self.ambient, "ambient"))
        object.__setattr__(self, "substrate", _check_medium(self.substrate, "substrate"))

    # -- convenience -----------------------------------------------------------------
    @property
    def n_layers(self) -> int:
        return len(self.layers)

    @property
    def coherent(self) -> bool:
        """True when every layer is coherent (complex amplitudes are then defined)."""
        return all(layer.coherent for layer in self.layers)

    def with_thicknesses(self, thickness_nm: Sequence) -> "Stack":
        """A copy with new layer thicknesses (one value or array per layer, in order)."""
        if len(thickness_nm) != self.n_layers:
            raise InvalidInputError(f"need {self.n_layers} thicknesses, got {len(thickness_nm)}")
        layers = [replace(layer, thickness_nm=d) for layer, d in zip(self.layers, thickness_nm)]
        return Stack(layers, ambient=self.ambient, substrate=self.substrate)

    def __repr__(self) -> str:
        inner = ", ".join(repr(layer) for layer in self.layers)
        return f"Stack([{inner}], ambient={_medium_name(self.ambient)}, substrate={_medium_name(self.substrate)})"

    # -- the calculation ---------------------------------------------------------------
    def rt(
        self,
        wavelength_nm,
        angle_deg=0.0,
        *,
        grid: bool = True,
        layer_absorption: bool = False,
        method: str = "auto",
    ) -> StackResult:
        """Reflectance, transmittance and (coherent stacks) amplitude coefficients.

        Parameters
        ----------
        wavelength_nm : array_like
            Vacuum wavelengths in nm, inside every material's range.
        angle_deg : array_like
            Angles of incidence in the ambient, degrees in ``[0, 90)``.
        grid : bool
            ``True`` (default): every wavelength with every angle, results of shape
            ``thickness_shape + wavelength.shape + angle.shape``. ``False``: wavelength
            and angle broadcast together (paired measurement points).
        layer_absorption : bool
            Also compute the absorbed fraction in each layer (``absorbed_s``,
            ``absorbed_p``, ``absorbed``).
        method : {'auto', 'numba', 'numpy'}
            Kernel for fully coherent stacks without per-layer absorption: a compiled
            Numba loop over points (fastest on large grids) or batched NumPy arithmetic
            (used in every other case). ``'auto'`` takes Numba from
            :data:`NUMBA_MIN_POINTS` result points up, so that small calls do not pay for
            loading the compiled kernel. Both give the same numbers to rounding.

        Returns
        -------
        StackResult
        """
        if method not in ("auto", "numba", "numpy"):
            raise InvalidInputError(f"method must be 'auto', 'numba' or 'numpy', got {method!r}")
        w = as_wavelength_nm(wavelength_nm)
        a = check_angle_deg(angle_deg)
        if grid:
            gshape = w.shape + a.shape
            w_g = w.reshape(w.shape + (1,) * a.ndim)
            a_g = a
        else:
            try:
                gshape = np.broadcast_shapes(w.shape, a.shape)
            except ValueError:
                raise InvalidInputError(
                    f"with grid=False wavelength_nm {w.shape} and angle_deg {a.shape} must broadcast together"
                ) from None
            w_g, a_g = w, a
        ng = len(gshape)

        def nk_of(medium, what):
            nk = _eval_nk(medium, w, what)
            return nk.reshape(w_g.shape) if grid else nk

        n_amb = nk_of(self.ambient, "ambient")
        n_sub = nk_of(self.substrate, "substrate")
        n_lay = [nk_of(layer.material, f"layer {i}") for i, layer in enumerate(self.layers)]
        d_lay = [layer.thickness_nm.reshape(layer.thickness_nm.shape + (1,) * ng) for layer in self.layers]
        dshape = np.broadcast_shapes(*(layer.thickness_nm.shape for layer in self.layers)) if self.layers else ()
        shape = dshape + gshape

        _warn_thick_coherent(self.layers, w, n_lay)
        theta = np.radians(a_g)
        coh = [layer.coherent for layer in self.layers]
        if method == "auto":
            method = "numba" if np.prod(shape, dtype=np.int64) >= NUMBA_MIN_POINTS else "numpy"
        if all(coh) and not layer_absorption and method == "numba":
            return _rt_numba(w, a, n_amb, n_lay, n_sub, d_lay, theta, w_g, shape)

        beta = n_amb * np.sin(theta)
        n_all = [n_amb] + n_lay + [n_sub]
        q_all = [n_amb * np.cos(theta)] + [n_cos_theta(n, beta) for n in n_lay + [n_sub]]
        k0 = 2 * np.pi / w_g

        if all(coh):
            res = {pol: coherent_rt(n_all, q_all, d_lay, k0, pol, flux=layer_absorption) for pol in "sp"}
        else:  # no phase for partly incoherent stacks: amplitudes stay None
            res = {pol: (None, None) + _incoherent_rt(n_all, q_all, d_lay, coh, k0, pol, layer_absorption)
                   for pol in "sp"}
        b = _broadcaster(shape)

        def amp(pol, i):
            return None if res[pol][i] is None else b(res[pol][i])

        def absorbed(pol):
            if not layer_absorption:
                return None
            return np.stack([b(x) for x in res[pol][4]]) if self.layers else np.zeros((0,) + shape)

        return StackResult(
            wavelength_nm=w,
            angle_deg=a,
            Rs=b(res["s"][2]),
            Rp=b(res["p"][2]),
            Ts=b(res["s"][3]),
            Tp=b(res["p"][3]),
            rs=amp("s", 0),
            rp=amp("p", 0),
            ts=amp("s", 1),
            tp=amp("p", 1),
            absorbed_s=absorbed("s"),
            absorbed_p=absorbed("p"),
        )


#: Narrowest fringe spacing (nm) a coherent layer may have before :meth:`Stack.rt` warns: a
#: spectrometer's bandwidth is ~1 nm or more, so finer fringes are never seen — the measured
#: quantity is their average, the incoherent result (Katsidis & Siapkas 2002).
COHERENT_MIN_FRINGE_NM = 1.0
#: Optical thickness n·d (nm) from which a coherent layer sampled more coarsely than its fringes
#: is warned about as aliased (a clear coat, a glass sheet); thinner films (interference pigments,
#: oxide layers, sparse test grids) are coherent by nature and are not.
THICK_OPTICAL_NM = 5000.0


def _warn_thick_coherent(layers, w, n_lay):
    """Warn when a coherent layer is so thick that its interference fringes are finer than any
    instrument resolves (< :data:`COHERENT_MIN_FRINGE_NM`) or, for an optical thickness above
    :data:`THICK_OPTICAL_NM`, than the wavelength grid samples (fewer than one sample per fringe:
    the result is aliased). The fringe spacing in wavelength
    is λ² / (2 n d) at normal incidence."""
    if not layers or w.size == 0:
        return
    lam = float(np.min(w))
    u = np.unique(w.ravel())
    step = float(np.max(np.diff(u))) if u.size >= 3 else 0.0
    for i, (layer, n) in enumerate(zip(layers, n_lay)):
        if not layer.coherent:
            continue
        nd = float(np.max(np.real(n))) * float(np.max(layer.thickness_nm))
        if not np.isfinite(nd) or nd <= 0:
            continue
        fringe = lam**2 / (2.0 * nd)
        aliased = step > 0 and fringe < step and nd >= THICK_OPTICAL_NM
        if fringe < COHERENT_MIN_FRINGE_NM or aliased:
            why = (f"finer than the {step:g} nm wavelength grid (the result is aliased)" if aliased
                   else f"finer than any spectrometer resolves (< {COHERENT_MIN_FRINGE_NM:g} nm)")
            warnings.warn(
                f"layer {i} ({_medium_name(layer.material)}, {float(np.max(layer.thickness_nm)):g} nm) is coherent but "
                f"its interference fringes are {fringe:.3g} nm apart at {lam:g} nm, {why}; a layer this thick "
                f"should be incoherent: Layer(material, thickness_nm, coherent=False) or the tuple "
                f"(material, thickness_nm, 'i')", UserWarning, stacklevel=3)


def _broadcaster(shape):
    def b(x):
        x = np.asarray(x)
        return x if x.shape == shape else np.array(np.broadcast_to(x, shape))

    return b


# ----------------------------------------------------------------------------------------
# kernels
# ----------------------------------------------------------------------------------------
def coherent_rt(n, q, d, k0, pol: str, flux: bool = False):
    """Batched characteristic-matrix solution of a coherent stack on plain arrays.

    Parameters
    ----------
    n : list of complex ndarray
        ``[n_incidence, n_1, ..., n_L, n_exit]``, mutually broadcastable.
    q : list of complex ndarray
        ``n cos θ`` in the same media (forward branch, :func:`~nmmm.layers.fresnel_equations.n_cos_theta`).
    d : list of ndarray
        The ``L`` thicknesses in nm (same length unit as ``2π/k0``).
    k0 : ndarray
        Vacuum wavenumber ``2π/λ`` (1/nm).
    pol : {'s', 'p'}
    flux : bool
        Also return the absorbed fraction per layer (list of ``L`` arrays).

    Returns
    -------
    r, t, R, T, absorbed
        Complex amplitude coefficients in the :mod:`nmmm.layers.fresnel_equations` convention,
        power R and T, and the per-layer absorption list (``None`` unless ``flux``).
    """
    L = len(d)
    if pol == "s":
        eta = list(q)
    elif pol == "p":
        eta = [ni * ni / qi for ni, qi in zip(n, q)]
    else:
        raise InvalidInputError(f"pol must be 's' or 'p', got {pol!r}")
    B = np.ones((), dtype=complex)
    C = eta[-1]
    phase = 0.0
    fl = [None] * L
    att = [None] * L
    for j in range(L, 0, -1):
        qd = q[j] * d[j - 1]
        e = np.exp(2j * k0 * qd)
        c = 0.5 * (1.0 + e)
        h = 0.5 * (1.0 - e)
        et = eta[j]
        B, C = c * B + (h / et) * C, (h * et) * B + c * C
        phase = phase + qd
        if flux:
            fl[j - 1] = (B * np.conj(C)).real
            att[j - 1] = np.abs(e)  # |exp(iδ)|²
    eta0 = eta[0]
    num = eta0 * B
    den = num + C
    r = (num - C) / den
    t_tan = 2.0 * eta0 * np.exp(1j * k0 * phase) / den
    re0 = eta0.real
    R = np.abs(r) ** 2
    T = np.abs(t_tan) ** 2 * eta[-1].real / re0
    if pol == "p":
        r = -r
        t = t_tan * (q[0] / n[0]) / (q[-1] / n[-1])
    else:
        t = t_tan
    absorbed = None
    if flux:
        norm = 4.0 * np.abs(eta0) ** 2 / (np.abs(den) ** 2 * re0)
        fluxes = []
        cum = 1.0
        for j in range(L):
            fluxes.append(fl[j] * cum * norm)
            cum = cum * att[j]
        fluxes.append(T)
        absorbed = [fluxes[j] - fluxes[j + 1] for j in range(L)]
    return r, t, R, T, absorbed


@numba.njit(cache=True, parallel=True, fastmath=False)
def _coherent_kernel(nk, d, k0, sin0, cos0, rs, rp, ts, tp, Rs, Rp, Ts, Tp):  # pragma: no cover - compiled
    """Per-point fused s and p characteristic-matrix recurrence (see :func:`coherent_rt`)."""
    M, N = nk.shape
    L = M - 2
    tol = 1e-12
    for i in numba.prange(N):
        n0 = nk[0, i]
        beta = n0 * sin0[i]
        b2 = beta * beta
        q0 = n0 * cos0[i]
        e0 = n0 * n0
        nsub = nk[M - 1, i]
        esub = nsub * nsub
        qsub = np.sqrt(esub - b2)
        if qsub.imag < -tol or (abs(qsub.imag) <= tol and qsub.real < 0):
            qsub = -qsub
        kk = k0[i]
        Bs = 1.0 + 0.0j
        Cs = qsub
        Bp = 1.0 + 0.0j
        Cp = esub / qsub
        phase = 0.0 + 0.0j
        for j in range(L, 0, -1):
            n = nk[j, i]
            eps = n * n
            q = np.sqrt(eps - b2)
            if q.imag < -tol or (abs(q.imag) <= tol and q.real < 0):
                q = -q
            qd = q * d[j - 1, i]
            e = np.exp(2j * kk * qd)
            c = 0.5 * (1.0 + e)
            h = 0.5 * (1.0 - e)
            Bs, Cs = c * Bs + (h / q) * Cs, (h * q) * Bs + c * Cs
            Bp, Cp = c * Bp + (h * q / eps) * Cp, (h * eps / q) * Bp + c * Cp
            phase += qd
        ph = np.exp(1j * kk * phase)
        den = q0 * Bs + Cs
        r = (q0 * Bs - Cs) / den
        t = 2.0 * q0 * ph / den
        rs[i] = r
        ts[i] = t
        Rs[i] = r.real * r.real + r.imag * r.imag
        Ts[i] = (t.real * t.real + t.imag * t.imag) * qsub.real / q0.real
        eta0 = e0 / q0
        etasub = esub / qsub
        den = eta0 * Bp + Cp
        r = (eta0 * Bp - Cp) / den
        t = 2.0 * eta0 * ph / den
        rp[i] = -r
        tp[i] = t * (q0 / n0) / (qsub / nsub)
        Rp[i] = r.real * r.real + r.imag * r.imag
        Tp[i] = (t.real * t.real + t.imag * t.imag) * etasub.real / eta0.real


def _rt_numba(w, a, n_amb, n_lay, n_sub, d_lay, theta, w_g, shape):
    """Flatten every input to the full result shape and run :func:`_coherent_kernel`."""
    N = int(np.prod(shape, dtype=np.int64))
    nk = np.empty((len(n_lay) + 2, N), dtype=complex)
    for j, x in enumerate([n_amb] + n_lay + [n_sub]):
        nk[j] = np.broadcast_to(x, shape).ravel()
    d = np.empty((len(d_lay), N), dtype=float)
    for j, x in enumerate(d_lay):
        d[j] = np.broadcast_to(x, shape).ravel()
    k0 = np.broadcast_to(2 * np.pi / w_g, shape).ravel()
    th = np.broadcast_to(theta, shape).ravel()
    sin0, cos0 = np.ascontiguousarray(np.sin(th)), np.ascontiguousarray(np.cos(th))
    k0 = np.ascontiguousarray(k0)
    rs, rp, ts, tp = (np.empty(N, dtype=complex) for _ in range(4))
    Rs, Rp, Ts, Tp = (np.empty(N, dtype=float) for _ in range(4))
    _coherent_kernel(nk, d, k0, sin0, cos0, rs, rp, ts, tp, Rs, Rp, Ts, Tp)
    f = lambda x: x.reshape(shape)  # noqa: E731
    return StackResult(w, a, f(Rs), f(Rp), f(Ts), f(Tp), f(rs), f(rp), f(ts), f(tp))


def _incoherent_rt(n, q, d, coh, k0, pol, layer_absorption):
    """Mixed coherent/incoherent stack (Katsidis & Siapkas 2002; Byrnes 2016 §5).

    Returns R, T and (optionally) the absorbed fraction per layer.
    """
    L = len(d)
    # incoherent media indices in the full list (0 = ambient, L+1 = substrate)
    inc = [0] + [j + 1 for j in range(L) if not coh[j]] + [L + 1]
    groups = []  # (top medium, bottom medium, coherent layer indices 1..L)
    for a, b in zip(inc[:-1], inc[1:]):
        groups.append((a, b, list(range(a + 1, b))))
    gres = []
    for a, b, members in groups:
        nf = [n[a]] + [n[j] for j in members] + [n[b]]
        qf = [q[a]] + [q[j] for j in members] + [q[b]]
        df = [d[j - 1] for j in members]
        _, _, Rf, Tf, Af = coherent_rt(nf, qf, df, k0, pol, flux=layer_absorption and bool(members))
        _, _, Rb, Tb, Ab = coherent_rt(nf[::-1], qf[::-1], df[::-1], k0, pol, flux=layer_absorption and bool(members))
        gres.append((Rf, Tf, Rb, Tb, Af, Ab))
    # single-pass intensity transmission of each incoherent layer
    P = {j: np.exp(-2.0 * k0 * q[j].imag * d[j - 1]) for j in inc[1:-1]}

    # bottom-up adding (power): reflectance seen from the top of each group
    m = len(groups)
    R_top = [None] * m  # reflectance of group g and everything below, from its top medium
    R_below = [None] * m  # reflectance of everything below group g, from its bottom medium
    t_group = [None] * m  # forward power ratio F(bottom of g) / F(top of g)
    acc = 0.0
    for g in range(m - 1, -1, -1):
        Rf, Tf, Rb, Tb, _, _ = gres[g]
        R_below[g] = acc
        denom = 1.0 - Rb * acc
        t_group[g] = Tf / denom
        R_top[g] = Rf + Tf * Tb * acc / denom
        if g > 0:
            Pj = P[groups[g][0]]
            acc = Pj * Pj * R_top[g]  # seen from the top of the incoherent layer above
    R = R_top[0]
    # top-down: forward power at the top of each group; T is what reaches the substrate
    F_top = [None] * m
    F = 1.0
    for g in range(m):
        F_top[g] = F
        F = F * t_group[g]
        if g < m - 1:
            F = F * P[groups[g][1]]
    T = F
    absorbed = None
    if layer_absorption:
        absorbed = [None] * L
        for g, (a, b, members) in enumerate(groups):
            Rf, Tf, Rb, Tb, Af, Ab = gres[g]
            F_bot = F_top[g] * t_group[g]  # forward power just below group g
            B_bot = F_bot * R_below[g]  # backward power arriving at its bottom
            for i, j in enumerate(members):
                absorbed[j - 1] = F_top[g] * Af[i] + B_bot * Ab[len(members) - 1 - i]
            if g < m - 1:
                # the incoherent layer b between groups g and g + 1: net Poynting flux
                # entering it from group g minus the flux leaving it into group g + 1.
                # Inside a group next to an absorbing incoherent medium the flux differs
                # from F(1 - R) by the interference of the counter-propagating waves, so
                # the fluxes just inside each group are used (as in tmm's inc_tmm).
                Rf1, Tf1, Rb1, Tb1, Af1, Ab1 = gres[g + 1]
                pe_b = Tb + (sum(Ab) if members else 0.0)  # flux leaving group g upwards, per unit B
                pe_f1 = Tf1 + (sum(Af1) if groups[g + 1][2] else 0.0)
                B_bot1 = F_top[g + 1] * t_group[g + 1] * R_below[g + 1]
                flux_in = F_top[g] * Tf - B_bot * pe_b
                flux_out = F_top[g + 1] * pe_f1 - B_bot1 * Tb1
                absorbed[b - 1] = flux_in - flux_out
    return R, T, absorbed
