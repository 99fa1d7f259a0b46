"""Backlash: a gap in series with the joint.

Physics: free play between the driven part and the joint (clearance in a clevis, a loose
band or a bolt hole before bearing). While the gap is open the joint carries no load: the
force is zero and the joint's history (its slider states) is frozen; the gap is crossed at
zero force and contact is made on the other side, where the joint is loaded again from the
state it was left in. After a reversal the joint first unloads along its own Masing branch
until its force is zero, and only then does the gap open. This is the dead-zone-in-series
form (a gap element in series with a hysteretic spring); its signature in a loop is a flat
zero-force segment of width ``2 gap`` after each reversal.
"""
from __future__ import annotations

from ._base import ParamSpec, _Effect, _find_zero

__all__ = ["Backlash"]


class Backlash(_Effect):
    """A dead zone of total width ``2 gap`` in series with the joint.

    The joint displacement ``w`` follows ``u - gap`` (contact pushing forward) or ``u + gap``
    (contact pushing back). When the motion reverses, the joint first unloads along its
    branch until its force is zero, then the gap opens and ``u`` crosses it at zero force
    until contact is made on the other side. In the virgin state the joint sits in the middle
    of the gap.

    Parameters
    ----------
    inner : joint element
    gap : float, keyword-only
        Half the dead-zone width [m], ``>= 0``.
    """

    effect = "backlash"
    specs = (ParamSpec("gap", "m", "half width of the free play in series with the joint",
                       ref="u_max", ref_power=-1, fit_bounds=(0.0, 0.5), fit_starts=(0.0, 0.01, 0.08)),)
    #: Gap values (fraction of the largest |u|) scanned for a start before the fit: the gap
    #: must land near the record's zero-force plateau before the joint's shape can follow.
    fit_scan = (0.0, 0.003, 0.006, 0.01, 0.015, 0.02, 0.03, 0.045, 0.06, 0.08, 0.1, 0.13, 0.17,
                0.22, 0.3)

    def __init__(self, inner, *, gap: float):
        super().__init__(inner)
        self._set_parameters({"gap": gap})
        self._reset_own()

    def _reset_own(self):
        self._w = 0.0
        self._side = 0           # +1 / -1: in contact pushing forward / back; 0: gap open

    @property
    def joint_displacement(self) -> float:
        """Committed displacement across the joint itself (excluding the gap) [m]."""
        return self._w

    def _solve(self, u: float, v: float):
        """Joint displacement ``w``, contact side, force and tangent at ``u``."""
        inner = self._inner
        g = self.gap
        wc = self._w
        side = self._side
        if side == 0:                            # resting in the gap at zero joint force
            w = min(max(wc, u - g), u + g)
            if w == wc:
                return wc, 0, inner.trial(wc, v)[0], 0.0
            F, K = inner.trial(w, v)
            return w, (1 if w > wc else -1), F, K
        w_contact = u - g * side
        F, K = inner.trial(w_contact, v)
        if (w_contact - wc) * side >= 0.0 or F * side > 0.0:
            return w_contact, side, F, K         # contact kept (loading or partial unloading)
        # the joint unloads to zero force, then the gap opens
        w0 = _find_zero(lambda x: inner.trial(x, v), wc, inner.force, w_contact, F)
        w_other = u + g * side
        if (w_other - w0) * side < 0.0:          # crossed the gap: contact on the other side
            F, K = inner.trial(w_other, v)
            return w_other, -side, F, K
        return w0, 0, inner.trial(w0, v)[0], 0.0

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m] (zero while the gap is open)."""
        w, side, F, K = self._solve(float(u), v)
        self._tw = w
        self._tside = side
        self._set_trial(u, v, F)
        return F, K

    def _commit(self) -> None:
        self._inner.trial(self._tw, self._tv)
        self._inner.commit()
        self._w = self._tw
        self._side = self._tside
        self._W = self._inner.work
        self._D = self._inner.dissipated_energy
