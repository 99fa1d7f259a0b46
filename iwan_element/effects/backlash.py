"""Backlash: a gap in series with the joint, closed through a compliant contact.

Physics: free play between the driven part and the joint (clearance in a clevis, a loose
band or a bolt hole before bearing). While the gap is open the joint carries no load: the
force is zero and the joint's history (its slider states) is frozen; the gap is crossed at
zero force and contact is made on the other side, where the joint is loaded again from the
state it was left in. After a reversal the joint first unloads along its own Masing branch
until its force is zero, and only then does the gap open. This is the dead-zone-in-series
form (a gap element in series with a hysteretic spring); its signature in a loop is a flat
zero-force segment of width ``2 gap`` after each reversal.

The contact that closes the gap is not rigid. Two curved bodies (a pin in a clevis hole, a
band wrapping onto its drum, the rounded faces of a loose linkage) touch at a point or a
line and the contact area grows with the load, so the contact *stiffens* with penetration.
Hertz's solution for curved elastic bodies gives the compression ``delta`` under a force
``P`` as ``P = (4/3) E* R^(1/2) delta^(3/2)`` (Johnson, *Contact Mechanics*, Cambridge
University Press 1985, eq. 4.23; a power law ``P ~ delta^n`` is the usual engineering form
of such contacts, e.g. Hunt and Crossley, J. Appl. Mech. 42 (1975) 440-445, and the
standard gap-contact element of multibody codes). Here the contact compresses by

    delta(F) = contact * |F|^(2/3)            (``contact``: compliance [m N^(-2/3)])

so that the gap-plus-contact is a nonlinear elastic spring with a dead zone,
``F = sign(e) ((|e| - gap)_+ / contact)^(3/2)`` for a stretch ``e = u - w`` across it, in
series with the joint (joint displacement ``w``); the force is found from the series
equilibrium ``F_joint(w) = F_contact(u - w)`` (one increasing function of ``w``). Where the
records show it, this is the shape of a re-engagement after the plateau: convex (soft while
the contact is light, stiffening with the load), where a rigid stop in series with the
concave Iwan branch can only rise concavely. The exponent 3/2 is Hertz's for curved bodies;
``contact = 0`` is the rigid stop (the dead zone alone) and reproduces it exactly.
"""
from __future__ import annotations

import math

from ._base import ParamSpec, _Effect, _find_zero

__all__ = ["Backlash"]

#: Exponent of the contact law ``F ~ delta^EXPONENT`` (Hertz, curved elastic bodies).
EXPONENT = 1.5


class Backlash(_Effect):
    """A dead zone of total width ``2 gap`` in series with the joint, closed through a Hertz
    contact (module docstring).

    The joint displacement ``w`` follows ``u - gap - delta(F)`` (contact pushing forward) or
    ``u + gap + delta(F)`` (pushing back), with the contact compression
    ``delta(F) = contact |F|^(2/3)``. When the motion reverses, the joint first unloads along
    its branch and the contact relaxes until the force is zero, then the gap opens and ``u``
    crosses it at zero force until contact is made on the other side. In the virgin state the
    joint sits in the middle of the gap.

    Parameters
    ----------
    inner : joint element
    gap : float, keyword-only
        Half the dead-zone width [m], ``>= 0``.
    contact : float, keyword-only
        Compliance of the contact that closes the gap [m N^(-2/3)], ``>= 0``: the contact
        compresses by ``contact |F|^(2/3)`` under the force ``F``. Default 0 (a rigid stop).
    """

    effect = "backlash"
    specs = (ParamSpec("gap", "m", "half width of the free play in series with the joint",
                       ref="u_max", ref_power=-1, fit_bounds=(0.0, 0.5), fit_starts=(0.0, 0.01, 0.08)),
             ParamSpec("contact", "m N^(-2/3)",
                       "compliance of the Hertz contact closing the gap: compression "
                       "contact |F|^(2/3)", default=0.0, fs_power=-2.0 / 3.0, ref="u_max",
                       ref_power=-1, fit_bounds=(0.0, 0.3), fit_starts=(0.0, 0.01, 0.03)))
    #: Gap values (fraction of the largest |u|) scanned for a start before the fit: the gap
    #: must land near the record's zero-force plateau before the joint's shape can follow.
    fit_scan = (0.0, 0.003, 0.006, 0.01, 0.015, 0.02, 0.03, 0.045, 0.06, 0.08, 0.1, 0.13, 0.17,
                0.22, 0.3)

    def __init__(self, inner, *, gap: float, contact: float = 0.0):
        super().__init__(inner)
        self._set_parameters({"gap": gap, "contact": contact})
        self._reset_own()

    def _reset_own(self):
        self._w = 0.0
        self._side = 0           # +1 / -1: in contact pushing forward / back; 0: gap open

    @property
    def joint_displacement(self) -> float:
        """Committed displacement across the joint itself (excluding gap and contact) [m]."""
        return self._w

    def compression(self, F: float) -> float:
        """Contact compression [m] under the force ``F`` [N] (signed like ``F``)."""
        return math.copysign(self.contact * abs(F) ** (1.0 / EXPONENT), F)

    def contact_force(self, e: float) -> tuple[float, float]:
        """Force [N] and stiffness [N/m] of gap plus contact at the stretch ``e`` [m] across
        them (``contact > 0``)."""
        pen = abs(e) - self.gap
        if pen <= 0.0:
            return 0.0, 0.0
        F = (pen / self.contact) ** EXPONENT
        return math.copysign(F, e), EXPONENT * F / pen

    def _solve(self, u: float, v: float):
        if self.contact > 0.0:
            return self._solve_compliant(u, v)
        return self._solve_rigid(u, v)

    def _solve_rigid(self, u: float, v: float):
        """Joint displacement ``w``, contact side, force and tangent at ``u`` (rigid stop)."""
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

    def _solve_compliant(self, u: float, v: float):
        """Series equilibrium ``h(w) = F_joint(w) - F_contact(u - w) = 0``: ``h`` increases
        with ``w`` (both parts have a non-negative tangent), so its root is bracketed by
        stepping away from the committed ``w`` and found by Newton steps safeguarded by
        bisection. Returns ``w``, side, force, series tangent."""
        inner = self._inner
        wc = self._w

        def h(w):
            Fj, Kj = inner.trial(w, v)
            Fc, Kc = self.contact_force(u - w)
            return Fj - Fc, Kj + Kc, Fj, Kj, Kc

        hc = h(wc)
        if hc[0] == 0.0:
            return self._finish(wc, hc)
        step = -math.copysign(max(abs(u - self._u), self.gap, 1e-12 * (abs(u) + abs(wc)),
                                  1e-300), hc[0])
        a, ha = wc, hc
        for _ in range(200):                     # bracket: h changes sign between a and b
            b = a + step
            hb = h(b)
            if hb[0] == 0.0 or (hb[0] > 0.0) != (ha[0] > 0.0):
                break
            a, ha, step = b, hb, 2.0 * step
        else:
            raise FloatingPointError("backlash: the series equilibrium was not bracketed")
        lo, hi = (a, b) if ha[0] < 0.0 else (b, a)
        w, hw = (b, hb) if abs(hb[0]) < abs(ha[0]) else (a, ha)
        scale = max(abs(ha[2]), abs(hb[2]), 1e-300)
        for _ in range(200):
            if abs(hw[0]) <= 1e-13 * scale or abs(hi - lo) <= 1e-15 * (abs(lo) + abs(hi)):
                break
            w_new = w - hw[0] / hw[1] if hw[1] > 0.0 else 0.5 * (lo + hi)
            if not min(lo, hi) < w_new < max(lo, hi):
                w_new = 0.5 * (lo + hi)
            w = w_new
            hw = h(w)
            if hw[0] < 0.0:
                lo = w
            else:
                hi = w
        return self._finish(w, hw)

    @staticmethod
    def _finish(w, hw):
        _, _, Fj, Kj, Kc = hw
        side = 0 if Fj == 0.0 else (1 if Fj > 0.0 else -1)
        K = Kj * Kc / (Kj + Kc) if Kj + Kc > 0.0 else 0.0      # springs in series
        return w, side, Fj, K

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
        # work = the joint's work plus the elastic energy stored in the contact,
        # int F d(delta) = |F| delta(F) / (EXPONENT + 1) for F ~ delta^EXPONENT
        F = self._inner.force
        self._W = self._inner.work + abs(F * self.compression(F)) / (EXPONENT + 1.0)
        self._D = self._inner.dissipated_energy
