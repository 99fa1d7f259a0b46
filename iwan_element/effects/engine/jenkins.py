"""Jenkins elements (a spring in series with a Coulomb slider) shared by the effects that
model a part of the interface starting to slide: their first-harmonic gain and a bank of
them replacing part of a joint's stuck stiffness.

A Jenkins element of stiffness ``k`` and slip displacement ``phi`` under ``u = X cos(theta)``
is elastic-perfectly-plastic (Caughey, J. Appl. Mech. 27:640-643, 1960; Iwan, J. Appl. Mech.
33:893-900, 1966). With ``cos(theta*) = 1 - 2 phi / X`` its in-phase first harmonic is
``k g(X, phi)``, ``g = (theta* - sin(theta*) cos(theta*)) / pi`` (1 while stuck,
``X <= phi``), and it dissipates ``4 k phi (X - phi)`` per cycle. Derivation:
``docs/vibration_effects.md``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...core.masing import jenkins_constants
from ...core.periodic import PeriodicForm
from ..base import Effect

__all__ = ["jenkins_gain", "JenkinsBank"]


def jenkins_gain(X, phi) -> NDArray[np.float64]:
    """First-harmonic (in-phase) stiffness of a Jenkins element at amplitude ``X`` [m] per
    unit spring stiffness [-]: 1 while stuck (``X <= phi``), ``(theta - sin theta cos
    theta)/pi`` with ``cos theta = 1 - 2 phi / X`` above.
    """
    X = np.asarray(X, float)
    c = np.clip(1.0 - 2.0 * phi / X, -1.0, 1.0)
    th = np.arccos(c)
    return (th - np.sin(th) * c) / np.pi


class JenkinsBank(Effect):
    """A bank of parallel Jenkins elements that replaces the same stiffness of the wrapped
    joint: ``F = F_j(u) + sum_i z_i - (sum_i k_i) u``, identical to the joint until the
    first element slides. Subclasses call :meth:`_set_bank` with the elements' slip
    displacements [m] and stiffnesses [N/m] after setting their parameters.
    """

    def _set_bank(self, phi, k) -> None:
        self._phi = np.asarray(phi, float)
        self._k = np.asarray(k, float)  # stiffness of each element [N/m]
        self._k_total = float(np.sum(self._k))
        self._lim = self._k * self._phi  # friction limits [N]
        self._reset_own()

    def _periodic_own(self) -> PeriodicForm:
        """The bank as Masing rows, one per Jenkins element
        (:func:`~iwan_element.core.masing.jenkins_constants`), with the stiffness it replaces
        taken off: ``sum_i z_i - (sum_i k_i) u``.
        """
        return PeriodicForm(jenkins_constants(self._k, self._phi), self._k_total)

    def _reset_own(self):
        self._z = np.zeros(self._k.size)  # committed element forces [N]
        self._Dp = 0.0  # energy dissipated by the bank's sliders [J]

    def _bank(self, u: float):
        """Trial element forces, the bank's tangent and the slip increment's dissipation."""
        z = self._z + self._k * (u - self._u)
        zc = np.clip(z, -self._lim, self._lim)
        # a sliding element's slip is |z - zc| / k, at the friction limit k phi
        dD = float(np.sum(self._phi * np.abs(z - zc)))
        return zc, float(np.sum(self._k[zc == z])), dD

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        z, kz, self._tdD = self._bank(u)
        self._tz = z
        F += float(np.sum(z)) - self._k_total * u
        self._set_trial(u, v, F)
        return F, K + kz - self._k_total

    def _commit(self) -> None:
        self._inner.commit()
        self._z = self._tz
        self._Dp += self._tdD
        stored = (
            0.5 * float(np.sum(self._z**2 / self._k)) if self._k_total > 0 else 0.0
        ) - 0.5 * self._k_total * self._tu**2
        self._W = self._inner.work + self._Dp + stored
        self._D = self._inner.dissipated_energy + self._Dp
