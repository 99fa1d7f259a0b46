"""Onset of macroslip over part of the interface: a stuck patch that starts to slide, all at
once or with its slip front moving in as the amplitude grows.

Physics: the calibrated joint carries part of its stuck stiffness in a region that, over
the calibrated amplitudes, never slips (a high-pressure patch under a bolt, or the region
between the pressure cones whose slip the low-amplitude test never reached). Above some
amplitude its tangential load reaches its friction limit and it starts to slide. Modelled
as Iwan's distributed-element model (Iwan, J. Appl. Mech. 33:893-900, 1966): parallel
Jenkins elements (a spring in series with a Coulomb slider; Caughey, J. Appl. Mech.
27:640-643, 1960, for its harmonic response) of total stiffness ``k_s`` whose slip
displacements start at ``u_s``: the stiffness fraction ``s`` in ``[0, 1)`` has slip
displacements below

    phi(s) = u_s (1 - s)^(-spread)          (:func:`patch_thresholds`)

(density ``~ phi^-(1 + 1/spread)`` above ``u_s``, finite total stiffness). ``spread = 0``
is a patch that slides as a whole (one Jenkins element). Reading: uniform tangential
stiffness per area and a contact pressure rising towards a peak as ``r^-m`` inside the
radius where it equals the onset pressure; the threshold is ``phi = mu p / k_t``, so
``spread = m / 2`` and the slip front moves inward with amplitude, as in Cattaneo-Mindlin
partial slip (Mindlin, J. Appl. Mech. 16:259-268, 1949). The patch replaces the part ``k_s``
of the joint's stuck stiffness:

    F = F_j(u) + P(u) - k_s u,

identical to the joint below ``u_s``. Above it each sliding element dissipates
``4 k phi (X - phi)`` per cycle and loses stiffness. A whole patch (``spread = 0``) adds a
damping ratio ``~ (X - X_s) / X^2``, which peaks at ``2 X_s`` and falls after; a spread patch
keeps adding sliding elements, so the damping it adds keeps growing well beyond ``2 X_s``.

Modal form (first harmonic, elastic-perfectly-plastic elements; ``s(X) = 1 - (X_s /
X)^(1/spread)`` the sliding fraction at ``X > X_s``):

    w(X)^2 = w_base(X)^2 - kappa_s int_0^s(X) (1 - g(X, phi(s))) ds,
    D(X)   = 4 kappa_s int_0^s(X) phi(s) (X - phi(s)) ds,
    zeta = zeta0 + (zeta_base - zeta0) w_base^2 / w^2 + D / (2 pi w^2 X^2),

with ``g`` the Jenkins element's first-harmonic gain (:func:`jenkins_gain`); the stiffness
integral by 48-point Gauss-Legendre quadrature (:func:`patch_stiffness_loss`), the
dissipation in closed form (:func:`patch_dissipation`). Equations and derivation:
``docs/vibration_effects.md``.

Joint (time-domain) form: a bank of ``bins`` Jenkins elements of stiffness ``k_s / bins``,
one per bin of equal stiffness, at the bin's median slip displacement ``phi((i + 1/2) /
bins)``: the stiffness is exact, the dissipation of the bins already sliding is off by their
spread within the bin, ``O(bins^-2)`` (measured in ``tests/test_vibration_effects.py``).
"""
from __future__ import annotations

import numpy as np

from ._base import ParamSpec
from ._jenkins import JenkinsBank, jenkins_gain

__all__ = ["MacroslipOnset", "patch_thresholds", "patch_stiffness_loss",
           "patch_dissipation"]


_GL = np.polynomial.legendre.leggauss(48)


def _neg_expm1_over(a, lam):
    """``-expm1(a lam) / a`` (``-lam`` at ``a = 0``), stable near ``a = 0``."""
    a = np.asarray(a, float)
    small = np.abs(a * lam) < 1e-8
    return np.where(small, -lam * (1.0 + 0.5 * a * lam),
                    -np.expm1(a * lam) / np.where(small, 1.0, a))


def patch_thresholds(s, X_s, spread):
    """Slip amplitude [m] below which the fraction ``s`` (in ``[0, 1)``) of the patch's
    stiffness lies: ``X_s (1 - s)^-spread`` (``X_s`` for every ``s`` at ``spread = 0``)."""
    return X_s * (1.0 - np.asarray(s, float)) ** (-spread)


def _sliding_fraction(X, X_s, spread):
    """Stiffness fraction of the patch sliding at amplitude ``X``: ``1 - (X_s/X)^(1/spread)``
    (0 below ``X_s``; 1 above it at ``spread = 0``)."""
    X = np.asarray(X, float)
    r = np.minimum(X_s / X, 1.0)
    if spread <= 0.0:
        return np.where(r < 1.0, 1.0, 0.0)
    return -np.expm1(np.log(r) / spread)


def patch_stiffness_loss(X, X_s, spread):
    """Lost first-harmonic stiffness of a patch of unit stiffness at amplitude ``X`` [-]:
    ``int_0^s(X) (1 - g(X, phi(s))) ds`` over the stiffness fraction ``s`` that slides
    (:func:`patch_thresholds`), by 48-point Gauss-Legendre quadrature
    (``spread = 0``: ``1 - jenkins_gain(X, X_s)``)."""
    X = np.asarray(X, float)
    if spread <= 0.0:
        return 1.0 - jenkins_gain(X, X_s)
    sx = _sliding_fraction(X, X_s, spread)
    x, w = _GL
    s = 0.5 * sx[..., None] * (1.0 + x)
    phi = patch_thresholds(s, X_s, spread)
    return 0.5 * sx * np.sum(w * (1.0 - jenkins_gain(X[..., None], phi)), axis=-1)


def patch_dissipation(X, X_s, spread):
    """Energy dissipated per cycle by a patch of unit stiffness at amplitude ``X`` [m^2 per
    unit stiffness]: ``4 int_0^s(X) phi (X - phi) ds``, closed form (module docstring;
    ``spread = 0``: ``4 X_s (X - X_s)``)."""
    X = np.asarray(X, float)
    r = np.minimum(X_s / X, 1.0)
    if spread <= 0.0:
        return np.where(r < 1.0, 4.0 * X_s * (X - X_s), 0.0)
    lam = np.log(r) / spread                     # ln(1 - s(X)) <= 0
    m1 = X_s * _neg_expm1_over(1.0 - spread, lam)
    m2 = X_s * X_s * _neg_expm1_over(1.0 - 2.0 * spread, lam)
    return 4.0 * (X * m1 - m2)


class MacroslipOnset(JenkinsBank):
    """A stuck patch of the interface that slides above ``u_s``: all at once
    (``spread = 0``), or its elements one after another, the stiffness fraction ``s`` once
    the slip exceeds ``u_s (1 - s)^-spread``.

    Parameters
    ----------
    inner : joint element
    k_s : float, keyword-only
        Tangential stiffness of the patch [N/m], ``>= 0``; part of the stuck stiffness of
        ``inner`` (the element equals ``inner`` below ``u_s``), so it must not exceed it.
    u_s : float, keyword-only
        Slip displacement at which the patch starts to slide [m], ``> 0``.
    spread : float, keyword-only
        Spread exponent of the patch's slip displacements [-], ``>= 0``: the stiffness
        fraction ``s`` has them below ``u_s (1 - s)^-spread`` (median ``u_s 2^spread``);
        0 (default): the patch slides as a whole.
    bins : int, keyword-only
        Jenkins elements of the time-domain bank when ``spread > 0`` (module docstring),
        ``>= 1``; default 32.
    """

    effect = "macroslip_onset"
    specs = (ParamSpec("k_s", "N/m", "stuck stiffness of the patch that slides", fs_power=1,
                       ref="u_max", fit_bounds=(0.0, 5.0), fit_starts=(0.0, 0.3, 1.0)),
             ParamSpec("u_s", "m", "slip displacement at which the patch starts to slide",
                       lower=0.0, default=None, ref="u_max", ref_power=-1,
                       fit_bounds=(0.02, 1.0), fit_starts=(0.5, 0.3, 0.7)),
             ParamSpec("spread", "1", "spread exponent of the patch's slip displacements, "
                       "u_s (1 - s)^-spread (0: slides as a whole)", default=0.0, fit_bounds=(0.0, 10.0),
                       fit_starts=(0.0, 0.0, 1.0)))
    modal_specs = (ParamSpec("kappa_s", "1/s^2", "patch stiffness over modal mass",
                             ref="omega2_ref", ref_power=-1, fit_bounds=(0.0, 0.3),
                             fit_starts=(0.0, 0.01, 0.05, 0.003, 0.02, 0.05, 0.02, 0.1)),
                   ParamSpec("X_s", "m", "amplitude at which the patch starts to slide",
                             ref="X_max", ref_power=-1, fit_bounds=(0.02, 1.0),
                             fit_starts=(0.5, 0.3, 0.6, 0.8, 0.8, 0.9, 0.4, 0.3)),
                   ParamSpec("spread", "1", "spread exponent of the slip amplitudes, "
                             "X_s (1 - s)^-spread (0: slides as a whole)",
                             default=0.0, fit_bounds=(0.0, 10.0),
                             fit_starts=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 3.0)))
    kind = "dissipation"

    def __init__(self, inner, *, k_s: float, u_s: float, spread: float = 0.0,
                 bins: int = 32):
        super().__init__(inner)
        self._set_parameters({"k_s": k_s, "u_s": u_s, "spread": spread})
        if self.u_s <= 0.0:
            raise ValueError(f"u_s must be > 0 [m], got {u_s!r}")
        if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 1:
            raise ValueError(f"bins must be an integer >= 1, got {bins!r}")
        n = 1 if self.spread == 0.0 else int(bins)
        # n bins of equal stiffness, each element at its bin's median slip displacement
        self._set_bank(patch_thresholds((np.arange(n) + 0.5) / n, self.u_s, self.spread),
                       np.full(n, self.k_s / n))

    @classmethod
    def modal_form(cls, X, frequency, damping, zeta0, *, kappa_s, X_s, spread=0.0):
        """Frequency [Hz] lowered by the lost stiffness of the sliding part of the patch and
        damping ratio [-] raised by its dissipation (module docstring)."""
        X = np.asarray(X, float)
        w2b = (2 * np.pi * frequency) ** 2
        w2 = w2b - kappa_s * patch_stiffness_loss(X, X_s, spread)
        w2 = np.maximum(w2, 1e-6 * w2b)
        D = kappa_s * patch_dissipation(X, X_s, spread)
        zeta = zeta0 + (damping - zeta0) * w2b / w2 + D / (2 * np.pi * w2 * X * X)
        return np.sqrt(w2) / (2 * np.pi), zeta

    @classmethod
    def modal_to_joint(cls, values, *, modal_mass, slip_per_amplitude, omega0):
        """Patch stiffness ``k_s = kappa_s m / r^2`` [N/m], onset ``u_s = X_s r`` [m], the
        spread exponent unchanged."""
        r = slip_per_amplitude
        return {"k_s": values["kappa_s"] * modal_mass / r ** 2, "u_s": values["X_s"] * r,
                "spread": values.get("spread", 0.0)}
