"""Onset of macroslip over part of the interface: a stuck patch that starts to slide, all at
once, or with its slip front moving in as the amplitude grows.

Physics: the calibrated joint carries part of its stuck stiffness in a region that, over
the calibrated amplitudes, never slips (a high-pressure patch under a bolt, or the region
between the pressure cones whose slip the low-amplitude test never reached). Above some
amplitude its tangential load reaches its friction limit and it starts to slide. Modelled
as Iwan's distributed-element model (Iwan, J. Appl. Mech. 33:893-900, 1966): parallel
Jenkins elements (a spring in series with a Coulomb slider; Caughey, J. Appl. Mech.
27:640-643, 1960, for its harmonic response) whose slip displacements start at ``u_s``. The
stiffness ``K(phi)`` of the elements with slip displacement in ``[u_s, phi]`` follows one
law with a shape ``v`` in ``[0, 1]`` (``q = 1/v - 3``):

    K(phi) = k_2 B(phi / u_s) / B(2),      B(r) = (1 - r^-q) / q   (ln r at q = 0)

(:func:`patch_cumulative`): a threshold density ``~ phi^-(q + 1)`` above ``u_s``, with
``k_2`` the stiffness that slides between ``u_s`` and ``2 u_s``. ``v = 0`` is a patch that
slides as a whole (one Jenkins element of stiffness ``k_2`` at ``u_s``); ``0 < v < 1/3``
thresholds that thin out above the onset (finite total stiffness ``k_2 / (1 - 2^-q)``);
``v = 1/3`` a density ``~ 1/phi``; ``v = 1/2`` thresholds spread evenly; ``v > 1/2``
thresholds that crowd in with the slip, up to a density ``~ phi`` at ``v = 1``. Reading: uniform
tangential stiffness per area and a slip threshold proportional to the contact pressure (``phi = mu
p / k_t``), so the law is the pressure profile inside the radius where the pressure equals the onset
pressure: a pressure peaked as ``r^-m`` gives ``q = 2/m``; a parabolic fall-off from the peak (``p_0
(1 - r^2/a^2)``: equal areas in equal pressure steps) gives ``v = 1/2``; a Hertzian dome (``p_0
sqrt(1 - r^2/a^2)``) gives ``v = 1``. The slip front moves inward as the amplitude grows, as in
Cattaneo-Mindlin partial slip (Mindlin, J. Appl. Mech. 16:259-268, 1949). The patch replaces the
part of the joint's stuck stiffness it holds,

    F = F_j(u) + P(u) - k_P u,

identical to the joint below ``u_s``. Above it each sliding element dissipates
``4 k phi (X - phi)`` per cycle and loses stiffness. A whole patch adds a damping ratio
``~ (X - X_s) / X^2``, which peaks at ``2 X_s`` and falls after; a spread patch keeps adding
sliding elements, and from ``v = 1/2`` on the damping it adds grows at least in proportion
to the amplitude (``~ X^(1 - q)``) well above the onset.

Modal form (first harmonic, elastic-perfectly-plastic elements; ``kappa_2`` the stiffness
per unit modal mass that slides between ``X_s`` and ``2 X_s``, ``c = kappa_2 / B(2)``,
``L = ln(X / X_s)`` and ``E(a) = expm1(a L) / a``):

    w(X)^2 = w_base(X)^2 - int_0^K(X) (1 - g(X, phi(K))) dK,
    D(X)   = 4 int phi (X - phi) dK = 4 c [X X_s E(1 - q) - X_s^2 E(2 - q)],
    zeta = zeta0 + (zeta_base - zeta0) w_base^2 / w^2 + D / (2 pi w^2 X^2),

with ``g`` the Jenkins element's first-harmonic gain (:func:`.engine.jenkins.jenkins_gain`); the
stiffness integral by 48-point Gauss-Legendre quadrature over the sliding stiffness ``K``
(:func:`patch_stiffness_loss`), the dissipation in closed form (:func:`patch_dissipation`).
Equations and derivation: ``docs/vibration_effects.md``.

Joint (time-domain) form: a bank of ``bins`` Jenkins elements of equal stiffness over the
thresholds in ``[u_s, u_e]``, each at its bin's median slip displacement; elements above
``u_e`` are left stuck (linear springs, part of the joint's stiffness), exact while the slip
stays below ``u_e`` (``u_e = inf`` is allowed where the total stiffness is finite,
``v < 1/3``). The stiffness is exact; the dissipation of the bins already sliding is off by
their spread within the bin, ``O(bins^-2)`` (measured in ``tests/test_vibration_effects.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..base.validation import check_scalar
from .base import ParamSpec
from .engine.jenkins import JenkinsBank, jenkins_gain

__all__ = ["MacroslipOnset", "patch_cumulative", "patch_stiffness_loss", "patch_dissipation"]


_GL = np.polynomial.legendre.leggauss(48)

#: Top of the time-domain bank over the onset when the joint form is made from the modal one.
SPAN = 8.0


def _q(shape):
    """Density exponent ``q = 1/v - 3`` of the shape ``v > 0``."""
    return 1.0 / shape - 3.0


def _E(a, L):
    """``expm1(a L) / a`` (``L`` at ``a = 0``), stable near ``a = 0``."""
    a = np.asarray(a, float)
    small = np.abs(a * L) < 1e-8
    return np.where(small, L * (1.0 + 0.5 * a * L), np.expm1(a * L) / np.where(small, 1.0, a))


def _b2(q):
    """``B(2) = (1 - 2^-q) / q`` (``ln 2`` at ``q = 0``): the law's stiffness between the
    onset and twice it, per unit of its density scale.
    """
    return _E(-q, np.log(2.0))


def patch_cumulative(phi, X_s, shape) -> NDArray[np.float64]:
    """Stiffness fraction ``K(phi) / k_2`` [-] of the patch with slip displacement in
    ``[X_s, phi]``: ``B(phi / X_s) / B(2)``, ``B(r) = (1 - r^-q) / q`` (module docstring;
    0 below ``X_s``, 1 above it at ``shape = 0``).
    """
    L = np.log(np.maximum(np.asarray(phi, float) / X_s, 1.0))
    if shape <= 0.0:
        return np.where(L > 0.0, 1.0, 0.0)
    q = _q(shape)
    return _E(-q, L) / _b2(q)


def _thresholds(kappa, X_s, shape):
    """Slip displacement [m] below which the stiffness fraction ``kappa`` (of ``k_2``) lies:
    the inverse of :func:`patch_cumulative`.
    """
    q = _q(shape)
    k = np.asarray(kappa, float) * _b2(q)
    t = k if q == 0.0 else -np.log1p(-q * k) / q
    return X_s * np.exp(t)


def patch_stiffness_loss(X, X_s, shape) -> NDArray[np.float64]:
    """Lost first-harmonic stiffness at amplitude ``X`` [m] per unit ``k_2`` [-]:
    ``int_0^K(X) (1 - g(X, phi(K))) dK`` over the stiffness that slides, by 48-point
    Gauss-Legendre quadrature (``shape = 0``: ``1 - jenkins_gain(X, X_s)``).
    """
    X = np.asarray(X, float)
    if shape <= 0.0:
        return np.where(X > X_s, 1.0 - jenkins_gain(X, X_s), 0.0)
    kx = patch_cumulative(X, X_s, shape)
    x, w = _GL
    kap = 0.5 * kx[..., None] * (1.0 + x)
    phi = _thresholds(kap, X_s, shape)
    return 0.5 * kx * np.sum(w * (1.0 - jenkins_gain(X[..., None], phi)), axis=-1)


def patch_dissipation(X, X_s, shape) -> NDArray[np.float64]:
    """Energy dissipated per cycle at amplitude ``X`` [m] per unit ``k_2`` [m^2]:
    ``4 int phi (X - phi) dK = 4 c [X X_s E(1 - q) - X_s^2 E(2 - q)]``, ``c = 1 / B(2)``, in
    closed form (module docstring; ``shape = 0``: ``4 X_s (X - X_s)``).
    """
    X = np.asarray(X, float)
    L = np.log(np.maximum(X / X_s, 1.0))
    if shape <= 0.0:
        return np.where(L > 0.0, 4.0 * X_s * (X - X_s), 0.0)
    q = _q(shape)
    c = 1.0 / _b2(q)
    return 4.0 * c * (X * X_s * _E(1.0 - q, L) - X_s * X_s * _E(2.0 - q, L))


class MacroslipOnset(JenkinsBank):
    """A stuck patch of the interface that slides above ``u_s``: all at once
    (``shape = 0``), or its elements one after another by the threshold law of the module
    docstring (``k_2`` of stiffness between ``u_s`` and ``2 u_s``).

    Parameters
    ----------
    inner : joint element
    k_2 : float, keyword-only
        Stiffness of the patch [N/m] whose slip displacements lie in ``[u_s, 2 u_s]`` (the
        whole patch at ``shape = 0``), ``>= 0``; the bank's stiffness is part of the stuck
        stiffness of ``inner`` (the element equals ``inner`` below ``u_s``).
    u_s : float, keyword-only
        Slip displacement at which the patch starts to slide [m], ``> 0``.
    shape : float, keyword-only
        Shape of the threshold law [-], in ``[0, 1]``: 0 (default) the patch slides as a
        whole; below 1/3 thresholds that thin out above ``u_s``; 1/2 evenly spread; above
        1/2 crowding in, up to a density ``~ phi`` at 1 (module docstring).
    u_e : float, optional, keyword-only
        Largest slip displacement of the time-domain bank [m], ``> u_s`` (elements above it
        stay stuck); default none (the whole law), allowed for ``shape < 1/3`` only (finite
        total stiffness).
    bins : int, keyword-only
        Jenkins elements of the time-domain bank when ``shape > 0``, ``>= 1``; default 32.
    """

    effect = "macroslip_onset"
    # the parameters, stored by _set_parameters from specs (SI units)
    k_2: float
    u_s: float
    shape: float
    specs = (
        ParamSpec(
            "k_2",
            "N/m",
            "stiffness of the patch that slides between u_s and 2 u_s",
            fs_power=1,
            ref="u_max",
            fit_bounds=(0.0, 5.0),
            prior=(0.0, 5.0),
            neutral=0.0,
            fit_starts=(0.0, 0.3, 1.0),
        ),
        ParamSpec(
            "u_s",
            "m",
            "slip displacement at which the patch starts to slide",
            lower=0.0,
            default=None,
            ref="u_max",
            ref_power=-1,
            fit_bounds=(0.02, 1.0),
            prior=(0.02, 1.0),
            fit_starts=(0.5, 0.3, 0.7),
        ),
        ParamSpec(
            "shape",
            "1",
            "shape of the threshold law (0: slides as a whole, 1/2: thresholds spread evenly)",
            upper=1.0,
            default=0.0,
            fit_bounds=(0.0, 0.5),
            prior=(0.0, 0.5),
            fit_starts=(0.0, 0.0, 0.3),
        ),
    )
    modal_specs = (
        ParamSpec(
            "kappa_2",
            "1/s^2",
            "stiffness over modal mass that slides between X_s and 2 X_s",
            ref="omega2_ref",
            ref_power=-1,
            fit_bounds=(0.0, 0.3),
            prior=(0.0, 0.3),
            neutral=0.0,
            fit_starts=(0.0, 0.01, 0.05, 0.003, 0.02, 0.05, 0.02, 0.01),
        ),
        ParamSpec(
            "X_s",
            "m",
            "amplitude at which the patch starts to slide",
            ref="X_max",
            ref_power=-1,
            fit_bounds=(0.02, 1.0),
            prior=(0.02, 1.0),
            fit_starts=(0.5, 0.3, 0.6, 0.8, 0.8, 0.9, 0.4, 0.3),
        ),
        ParamSpec(
            "shape",
            "1",
            "shape of the threshold law (0: slides as a whole, 1/2: thresholds spread evenly)",
            upper=1.0,
            default=0.0,
            fit_bounds=(0.0, 0.5),
            prior=(0.0, 0.5),
            fit_starts=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.45),
        ),
    )
    kind = "dissipation"
    options = ("u_e", "bins")

    def __init__(
        self,
        inner,
        *,
        k_2: float,
        u_s: float,
        shape: float = 0.0,
        u_e: float | None = None,
        bins: int = 32,
    ):
        super().__init__(inner)
        self._set_parameters({"k_2": k_2, "u_s": u_s, "shape": shape})
        self.u_e = math.inf if u_e is None else check_scalar("u_e", u_e, low=0.0)
        if self.u_s <= 0.0:
            raise ValueError(f"u_s must be > 0 [m], got {u_s!r}")
        if not self.u_e > self.u_s:
            raise ValueError(f"u_e must be > u_s = {self.u_s!r} [m], got {u_e!r}")
        if math.isinf(self.u_e) and self.shape > 0.0 and _q(self.shape) <= 0.0:
            raise ValueError(
                f"u_e [m] must be given for shape >= 1/3 (an unbounded patch "
                f"would hold infinite stiffness), got shape={shape!r}"
            )
        if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 1:
            raise ValueError(f"bins must be an integer >= 1, got {bins!r}")
        if self.shape == 0.0:
            self._set_bank([self.u_s], [self.k_2])
            return
        # bins of equal stiffness over [u_s, u_e], each element at its bin's median threshold
        top = float(patch_cumulative(self.u_e, self.u_s, self.shape))  # 1 / (q B(2)) at inf
        kap = (np.arange(bins) + 0.5) / bins * top
        self._set_bank(_thresholds(kap, self.u_s, self.shape), np.full(bins, self.k_2 * top / bins))

    @classmethod
    def modal_form(cls, X, frequency, damping, zeta0, *, kappa_2, X_s, shape=0.0):
        """Frequency [Hz] lowered by the lost stiffness of the sliding part of the patch and
        damping ratio [-] raised by its dissipation (module docstring).
        """
        X = np.asarray(X, float)
        w2b = (2 * np.pi * frequency) ** 2
        w2 = np.maximum(w2b - kappa_2 * patch_stiffness_loss(X, X_s, shape), 1e-6 * w2b)
        D = kappa_2 * patch_dissipation(X, X_s, shape)
        zeta = zeta0 + (damping - zeta0) * w2b / w2 + D / (2 * np.pi * w2 * X * X)
        return np.sqrt(w2) / (2 * np.pi), zeta

    @classmethod
    def modal_to_joint(cls, values, *, modal_mass, slip_per_amplitude, omega0):
        """Stiffness ``k_2 = kappa_2 m / r^2`` [N/m], onset ``u_s = X_s r`` [m], the shape
        unchanged; the bank reaches ``u_e = SPAN u_s`` (``SPAN = 8``: exact for slips up to
        eight times the onset, its bins where a ring-down slides).
        """
        r = slip_per_amplitude
        u_s = values["X_s"] * r
        return {
            "k_2": values["kappa_2"] * modal_mass / r**2,
            "u_s": u_s,
            "shape": values.get("shape", 0.0),
            "u_e": SPAN * u_s,
        }
