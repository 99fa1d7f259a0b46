"""Backlash: a gap in series with the joint, crossed against a small drag friction.

Physics: free play between the driven part and the joint (clearance in a clevis, a loose
band or a bolt hole before bearing). While the gap is open the joint carries only what it
takes to move the free part across the gap; the joint's history (its slider states) is
frozen at that force; contact is made on the other side, where the joint is loaded again
from the state it was left in. After a reversal the joint first unloads along its own
Masing branch, and only then does the gap open. This is the dead-zone-in-series form (a gap
element in series with a hysteretic spring, e.g. Nordin and Gutman, Automatica 38 (2002)
1633-1649); its signature in a loop is a plateau of width ``2 gap`` after each
reversal.

The part that crosses the gap is not free: a loose link slides on its pin, a slack band
rubs its drum, a rod passes a seal. That rubbing is a Coulomb friction ``drag`` in series
with the joint *inside* the gap: the gap opening ``e = u - w`` (``w``: the joint's own
displacement) sticks while ``|F| < drag``, slides at ``F = +-drag`` against the motion, and
stops at the hard contacts ``e = +-gap``. The plateau therefore sits at ``-drag`` when the
drive moves back and at ``+drag`` when it moves forward (a rigid-plastic element with a
stroke limit in series with the joint), and each crossing dissipates ``2 gap drag``. The
ARTS friction-damper records show this: their plateaus lie a few per cent of the sliding
force on the side of the motion. ``drag = 0`` is the free gap crossed at zero force, which
this element reproduces exactly.

A compliant Hertz contact closing the gap (``F ~ delta^(3/2)``, a convex re-engagement) was
tried as the engagement law and rejected by the same records: refitted with the joint's
shape, its compliance goes to zero (see the project notes of the damper work).
"""

from __future__ import annotations

import copy

import numpy as np

from .base import Effect, ParamSpec, _find_zero, monotone_runs

__all__ = ["Backlash"]


def _shifted(FK, f):
    return FK[0] - f, FK[1]


class Backlash(Effect):
    """A dead zone of total width ``2 gap`` in series with the joint, crossed against a
    friction ``drag`` (module docstring).

    The joint displacement ``w`` follows ``u - gap`` (contact pushing forward) or
    ``u + gap`` (contact pushing back). When the motion reverses, the joint first unloads
    along its branch until its force is ``-+drag``, then the gap opens and ``u`` crosses it
    at that force until contact is made on the other side. In the virgin state the joint
    sits in the middle of the gap.

    Parameters
    ----------
    inner : joint element
    gap : float, keyword-only
        Half the dead-zone width [m], ``>= 0``.
    drag : float, keyword-only
        Friction force [N] resisting the motion across the open gap, ``>= 0`` (default 0:
        the gap is crossed at zero force).
    """

    effect = "backlash"
    structure = "series"
    loop_rank = 30
    # the parameters, stored by _set_parameters from specs (SI units)
    gap: float
    drag: float
    specs = (
        ParamSpec(
            "gap",
            "m",
            "half width of the free play in series with the joint",
            ref="u_max",
            ref_power=-1,
            fit_bounds=(0.0, 0.5),
            prior=(0.0, 0.5),
            neutral=0.0,
            fit_starts=(0.0, 0.01, 0.08),
        ),
        ParamSpec(
            "drag",
            "N",
            "friction force resisting the motion across the open gap",
            default=0.0,
            fs_power=1,
            fit_bounds=(0.0, 0.5),
            prior=(0.0, 0.5),
            neutral=0.0,
            fit_starts=(0.0, 0.05, 0.1),
        ),
    )
    #: Gap values (fraction of the largest |u|) scanned for a start before the fit: the gap
    #: must land near the record's zero-force plateau before the joint's shape can follow.
    fit_scan = (
        0.0,
        0.003,
        0.006,
        0.01,
        0.015,
        0.02,
        0.03,
        0.045,
        0.06,
        0.08,
        0.1,
        0.13,
        0.17,
        0.22,
        0.3,
    )

    def __init__(self, inner, *, gap: float, drag: float = 0.0):
        super().__init__(inner)
        self._set_parameters({"gap": gap, "drag": drag})
        self._reset_own()

    def _reset_own(self):
        self._e = 0.0  # opening of the gap (u - w) while drag acts, in [-gap, gap]
        self._Dg = 0.0  # energy dissipated by the drag [J]
        self._w = 0.0
        self._side = 0  # +1 / -1: in contact pushing forward / back; 0: gap open
        self._slide_at = None  # joint displacement where the last trial's gap began to slide

    @property
    def joint_displacement(self) -> float:
        """Committed displacement across the joint itself (excluding the gap) [m]."""
        return self._w

    def joint_path(self, u) -> np.ndarray:
        """Displacement across the joint itself [m] along a history ``u`` [m] from the virgin
        state, on a private copy (this element is untouched), for a rate-independent inner
        joint: one trial per monotone run of ``u``. Within a run of direction ``d`` the joint
        follows the drive with the gap's opening held (``w = u - e0``) until its force
        reaches ``d drag``, where the gap slides open (``w`` held at that point ``w_s``),
        until contact on the far side (``w = u - d gap``); the run's trial gives ``w_s``.
        So ``w = max(min(u - e0, w_s), u - gap)`` for ``d = +1`` (mirrored for ``-1``), the
        element's own per-sample steps (checked in ``tests/test_effects.py``).
        """
        uu = np.asarray(u, float)
        el = copy.deepcopy(self)
        el.reset()
        w = np.zeros(uu.size)
        g, u_prev, w_prev = self.gap, 0.0, 0.0
        for a, b, d in monotone_runs(uu):
            e0 = u_prev - w_prev
            el.trial(uu[b - 1])
            ws = el._slide_at
            seg = uu[a:b]
            if d > 0.0:
                w[a:b] = np.maximum(np.minimum(seg - e0, np.inf if ws is None else ws), seg - g)
            else:
                w[a:b] = np.minimum(np.maximum(seg - e0, -np.inf if ws is None else ws), seg + g)
            el.commit()
            u_prev, w_prev = float(uu[b - 1]), el.joint_displacement
            w[b - 1] = w_prev
        return w

    def _solve(self, u: float, v: float):
        if self.drag > 0.0:
            return self._solve_drag(u, v)
        return self._solve_rigid(u, v)

    def _solve_drag(self, u: float, v: float):
        """Rigid stops with a friction ``drag`` across the gap: the gap opening ``e = u - w``
        sticks while ``|F| < drag`` (or while pressed against a stop), slides at
        ``F = +-drag`` otherwise, up to the stop at ``+-gap``.
        """
        inner, g, fd, wc, ec = self._inner, self.gap, self.drag, self._w, self._e
        self._slide_at = None
        w = u - ec
        F, K = inner.trial(w, v)  # gap element stuck
        for s in (1.0, -1.0):
            if s * F <= fd or self._side == s:  # stuck, or pressed against that stop
                continue
            Fc = inner.force - s * fd  # committed joint force is inside +-drag
            if s * Fc >= 0.0:  # (up to rounding: at +-drag already)
                w_s = wc
            else:
                w_s = _find_zero(
                    lambda x, s=s: _shifted(inner.trial(x, v), s * fd), wc, Fc, w, F - s * fd
                )
            self._slide_at = w_s
            if s * (u - w_s) >= g:  # slid up to the stop: contact there
                w = u - s * g
                F, K = inner.trial(w, v)
                return w, int(s), F, K
            return w_s, 0, s * fd, 0.0
        return w, self._side, F, K

    def _solve_rigid(self, u: float, v: float):
        """Joint displacement ``w``, contact side, force and tangent at ``u`` (rigid stop)."""
        inner = self._inner
        g = self.gap
        wc = self._w
        side = self._side
        self._slide_at = None
        if side == 0:  # resting in the gap at zero joint force
            self._slide_at = wc
            w = min(max(wc, u - g), u + g)
            if w == wc:
                return wc, 0, inner.trial(wc, v)[0], 0.0
            F, K = inner.trial(w, v)
            return w, (1 if w > wc else -1), F, K
        w_contact = u - g * side
        F, K = inner.trial(w_contact, v)
        if (w_contact - wc) * side >= 0.0 or F * side > 0.0:
            return w_contact, side, F, K  # contact kept (loading or partial unloading)
        # the joint unloads to zero force, then the gap opens
        w0 = _find_zero(lambda x: inner.trial(x, v), wc, inner.force, w_contact, F)
        self._slide_at = w0
        w_other = u + g * side
        if (w_other - w0) * side < 0.0:  # crossed the gap: contact on the other side
            F, K = inner.trial(w_other, v)
            return w_other, -side, F, K
        return w0, 0, inner.trial(w0, v)[0], 0.0

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m] (zero tangent while the gap slides open)."""
        w, side, F, K = self._solve(float(u), v)
        self._te = (
            0.0
            if self.drag == 0.0
            else side * self.gap
            if side
            else min(max(float(u) - w, -self.gap), self.gap)
        )
        self._tw = w
        self._tside = side
        self._set_trial(u, v, F)
        return F, K

    def _commit(self) -> None:
        self._inner.trial(self._tw, self._tv)
        self._inner.commit()
        self._w = self._tw
        self._side = self._tside
        self._Dg += self.drag * abs(self._te - self._e)
        self._e = self._te
        self._W = self._inner.work + self._Dg  # the drag's work is all dissipated
        self._D = self._inner.dissipated_energy + self._Dg
