"""Onset of macroslip over part of the interface: a stuck patch that starts to slide as a whole.

Physics: the calibrated joint carries part of its stuck stiffness in a region that, over
the calibrated amplitudes, never slips (a high-pressure patch under a bolt, or the region
between the pressure cones whose slip the low-amplitude test never reached). Above some
amplitude its tangential load reaches its friction limit ``mu N_p`` and it slides as a whole:
a Jenkins element (a spring ``k_s`` in series with a Coulomb slider of strength
``F_s = k_s u_s``; Iwan, J. Appl. Mech. 33:893-900, 1966, the building block of the
distributed-element model; Caughey, J. Appl. Mech. 27:640-643, 1960, for its harmonic
response) that replaces the part ``k_s`` of the joint's stuck stiffness:

    F = F_j(u) + J(u) - k_s u,

identical to the joint below the slip displacement ``u_s``. Above it the patch dissipates
``4 F_s (X - u_s)`` per cycle and loses stiffness, so damping grows with amplitude faster
than the calibrated microslip law allows while the frequency drops a little more.

Modal form (first harmonic of the Jenkins element, elastic-perfectly-plastic): with
``cos(theta) = 1 - 2 X_s / X`` for ``X > X_s``,
``g(X) = (theta - sin(theta) cos(theta)) / pi`` (1 below ``X_s``),

    w(X)^2 = w_base(X)^2 - kappa_s (1 - g(X)),
    zeta = zeta0 + (zeta_base - zeta0) w_base^2 / w^2
           + 4 kappa_s X_s (X - X_s) / (2 pi w^2 X^2)   (X > X_s).

Equations: ``docs/vibration_effects.md``.
"""
from __future__ import annotations

import math

import numpy as np

from ._base import ParamSpec, _Effect

__all__ = ["MacroslipOnset", "jenkins_gain"]


def jenkins_gain(X, X_s):
    """First-harmonic (in-phase) stiffness of a Jenkins element at amplitude ``X`` per unit
    spring stiffness [-]: 1 while stuck (``X <= X_s``), ``(theta - sin theta cos theta)/pi``
    with ``cos theta = 1 - 2 X_s / X`` above."""
    X = np.asarray(X, float)
    c = np.clip(1.0 - 2.0 * X_s / X, -1.0, 1.0)
    th = np.arccos(c)
    return (th - np.sin(th) * c) / np.pi


class MacroslipOnset(_Effect):
    """A stuck patch of the interface that slides as a whole above ``u_s``.

    Parameters
    ----------
    inner : joint element
    k_s : float, keyword-only
        Tangential stiffness of the patch [N/m], ``>= 0``; part of the stuck stiffness of
        ``inner`` (the element equals ``inner`` below ``u_s``), so it must not exceed it.
    u_s : float, keyword-only
        Slip displacement of the patch [m], ``> 0`` (its friction limit is ``k_s u_s`` [N]).
    """

    effect = "macroslip_onset"
    specs = (ParamSpec("k_s", "N/m", "stuck stiffness of the patch that slides", fs_power=1,
                       ref="u_max", fit_bounds=(0.0, 5.0), fit_starts=(0.0, 0.3, 1.0)),
             ParamSpec("u_s", "m", "slip displacement of the patch", lower=0.0,
                       default=None, ref="u_max", ref_power=-1, fit_bounds=(0.02, 1.0),
                       fit_starts=(0.5, 0.3, 0.7)))
    modal_specs = (ParamSpec("kappa_s", "1/s^2", "patch stiffness over modal mass",
                             ref="omega2_ref", ref_power=-1, fit_bounds=(0.0, 0.3),
                             fit_starts=(0.0, 0.01, 0.05, 0.003, 0.02, 0.05)),
                   ParamSpec("X_s", "m", "amplitude at which the patch starts to slide",
                             ref="X_max", ref_power=-1, fit_bounds=(0.02, 1.0),
                             fit_starts=(0.5, 0.3, 0.6, 0.8, 0.8, 0.9)))
    kind = "dissipation"

    def __init__(self, inner, *, k_s: float, u_s: float):
        super().__init__(inner)
        self._set_parameters({"k_s": k_s, "u_s": u_s})
        if self.u_s <= 0.0:
            raise ValueError(f"u_s must be > 0 [m], got {u_s!r}")
        self._reset_own()

    def _reset_own(self):
        self._z = 0.0        # committed patch force [N]
        self._Dp = 0.0       # energy dissipated by the patch's slider [J]

    @classmethod
    def modal_form(cls, X, frequency, damping, zeta0, *, kappa_s, X_s):
        """Frequency [Hz] lowered by the lost stiffness of the sliding patch and damping
        ratio [-] raised by its dissipation (module docstring)."""
        X = np.asarray(X, float)
        w2b = (2 * np.pi * frequency) ** 2
        w2 = w2b - kappa_s * (1.0 - jenkins_gain(X, X_s))
        w2 = np.maximum(w2, 1e-6 * w2b)
        D = 4.0 * kappa_s * X_s * np.maximum(X - X_s, 0.0)
        zeta = zeta0 + (damping - zeta0) * w2b / w2 + D / (2 * np.pi * w2 * X * X)
        return np.sqrt(w2) / (2 * np.pi), zeta

    @classmethod
    def modal_to_joint(cls, values, *, modal_mass, slip_per_amplitude, omega0):
        """Patch stiffness ``k_s = kappa_s m / r^2`` [N/m], slip ``u_s = X_s r`` [m]."""
        r = slip_per_amplitude
        return {"k_s": values["kappa_s"] * modal_mass / r ** 2, "u_s": values["X_s"] * r}

    def _patch(self, u: float) -> tuple[float, float, float]:
        """Trial patch force, its tangent and the slip increment's dissipation."""
        lim = self.k_s * self.u_s
        z = self._z + self.k_s * (u - self._u)
        if abs(z) <= lim:
            return z, self.k_s, 0.0
        zc = math.copysign(lim, z)
        return zc, 0.0, lim * abs(z - zc) / self.k_s if self.k_s > 0 else 0.0

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        z, kz, self._tdD = self._patch(u)
        self._tz = z
        F += z - self.k_s * u
        self._set_trial(u, v, F)
        return F, K + kz - self.k_s

    def _commit(self) -> None:
        self._inner.commit()
        self._z = self._tz
        self._Dp += self._tdD
        stored = (0.5 * self._z ** 2 / self.k_s if self.k_s > 0 else 0.0) \
            - 0.5 * self.k_s * self._tu ** 2
        self._W = self._inner.work + self._Dp + stored
        self._D = self._inner.dissipated_energy + self._Dp
