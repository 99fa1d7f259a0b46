"""Physical effects the four-parameter Iwan model lacks, as joint elements.

Each effect wraps another joint element (an :class:`~iwan_element.IwanJoint`, a
:class:`~iwan_element.DiscreteIwan` or another effect, so effects stack) and reduces
*exactly* to it when its extra parameters are zero. All follow the element protocol
(``trial``/``commit``/``revert``/``reset`` and the energy read-outs).

========================  =====================================================================
name                      force law
========================  =====================================================================
``viscous_damping``       ``F = F_j(u) + c v`` (a dashpot in parallel)
``pinning_stiffness``     ``F = F_j(u) + k_p sign(u) max(|u| - delta, 0)`` (residual stiffness
                          after macroslip when ``delta = 0``; shank bearing on the hole after a
                          clearance ``delta > 0``)
``backlash``              a dead zone of total width ``2 gap`` in series with the joint: after a
                          reversal the joint unloads to zero force and is then carried through
                          the gap at zero force
``slip_degradation``      ``F = lambda F_j``, ``lambda = exp(-rate D_j)``: the joint's capacity
                          (slip force and stiffness, i.e. the contact) decays with the energy
                          ``D_j`` it has dissipated (wear, preload loss); later cycles are smaller
``asymmetric_slip``       ``F = (1 + a) F_j`` where ``F_j > 0`` and ``(1 - a) F_j`` where
                          ``F_j < 0``: slip capacity ``Fs (1 + a)`` forward, ``Fs (1 - a)`` back
========================  =====================================================================
"""
from __future__ import annotations

import copy
import inspect
import math

import numpy as np

from .core._validation import check_scalar, finite_array, same_length
from .core.protocol import check_element

__all__ = [
    "EFFECTS",
    "ViscousDamping",
    "PinningStiffness",
    "Backlash",
    "SlipDegradation",
    "AsymmetricSlip",
    "make_effect",
    "base_joint",
]


def _find_zero(trial, a: float, Fa: float, b: float, Fb: float, *, rtol: float = 1e-13,
               max_iter: int = 100) -> float:
    """Zero of a force monotone along the path ``a -> b`` (``Fa``, ``Fb`` of opposite sign),
    by Newton steps on the element's tangent, safeguarded by bisection. ``trial(x)`` returns
    ``(force, tangent)`` for the move from the committed state to ``x``."""
    lo, hi = (a, b) if Fa < 0.0 else (b, a)          # F(lo) < 0 < F(hi)
    x = a
    F = Fa
    K = trial(a + 1e-9 * (b - a))[1]
    scale = max(abs(Fa), abs(Fb))
    for _ in range(max_iter):
        x_new = x - F / K if K > 0.0 else 0.5 * (lo + hi)
        if not (min(lo, hi) < x_new < max(lo, hi)):
            x_new = 0.5 * (lo + hi)
        x = x_new
        F, K = trial(x)
        if abs(F) <= rtol * scale or abs(hi - lo) <= 1e-15 * max(abs(a), abs(b), 1e-300):
            break
        if F < 0.0:
            lo = x
        else:
            hi = x
    return x


class _Effect:
    """Shared plumbing: the wrapped element, energy counters and a generic force history."""

    effect = ""
    parameter_names: tuple = ()

    def __init__(self, inner):
        check_element(inner, name="inner")
        self._inner = inner
        self._W = self._D = self._F = self._u = 0.0
        self._has_trial = False

    @property
    def inner(self):
        """The wrapped joint element."""
        return self._inner

    @property
    def parameters(self) -> dict:
        """The effect's own parameters (SI units)."""
        return {k: getattr(self, k) for k in self.parameter_names}

    @property
    def params(self):
        """Parameters of the underlying Iwan joint."""
        return self._inner.params

    def describe(self) -> str:
        """One line naming this effect and every effect below it."""
        own = ", ".join(f"{k}={v:.4g}" for k, v in self.parameters.items())
        below = self._inner.describe() if isinstance(self._inner, _Effect) else repr(self._inner.params)
        return f"{self.effect}({own}) on {below}"

    def reset(self) -> None:
        """Virgin state, energy counters zero (the wrapped element too)."""
        self._inner.reset()
        self._W = 0.0
        self._D = 0.0
        self._F = 0.0
        self._u = 0.0
        self._reset_own()
        self.revert()

    def _reset_own(self) -> None:
        pass

    def revert(self) -> None:
        """Discard the last trial."""
        self._inner.revert()
        self._has_trial = False

    def _set_trial(self, u: float, v: float, F: float) -> None:
        self._tu = float(u)
        self._tv = float(v)
        self._tF = F
        self._has_trial = True

    def commit(self) -> None:
        """Accept the last trial (no-op if there is none)."""
        if not self._has_trial:
            return
        self._commit()
        self._F = self._tF
        self._u = self._tu
        self._has_trial = False

    def _commit(self) -> None:
        raise NotImplementedError

    @property
    def force(self) -> float:
        """Committed force [N]."""
        return self._F

    @property
    def displacement(self) -> float:
        """Committed displacement [m]."""
        return self._u

    @property
    def work(self) -> float:
        """Work done on the element since the last reset [J]."""
        return self._W

    @property
    def dissipated_energy(self) -> float:
        """Energy dissipated since the last reset [J]."""
        return self._D

    @property
    def stored_energy(self) -> float:
        """Recoverable energy [J]: work minus dissipation."""
        return self._W - self._D

    def force_history(self, u, v=None) -> np.ndarray:
        """Forces [N] for a history ``u`` [m] (and velocities ``v`` [m/s], default zero), shape
        (n,), from the virgin state, on a private copy; this element is untouched."""
        uu = finite_array("u", u, ndim=1)
        vv = np.zeros_like(uu) if v is None else finite_array("v", v, ndim=1)
        same_length(u=uu, v=vv)
        el = copy.deepcopy(self)
        el.reset()
        out = np.empty_like(uu)
        for i, (a, b) in enumerate(zip(uu.tolist(), vv.tolist())):
            out[i] = el.trial(a, b)[0]
            el.commit()
        return out

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.describe()}>"


class ViscousDamping(_Effect):
    """A dashpot in parallel with the joint: ``F = F_j + c v``.

    Parameters
    ----------
    inner : joint element
    c : float, keyword-only
        Damping coefficient [N s/m], ``>= 0``.

    Notes
    -----
    The dashpot's dissipation over a step is ``c (v_0 + v_1)/2 (u_1 - u_0)`` (the trapezoidal
    value of ``int c v du``), exact when the velocity is linear in time over the step.
    """

    effect = "viscous_damping"
    parameter_names = ("c",)

    def __init__(self, inner, *, c: float):
        super().__init__(inner)
        self.c = check_scalar("c", c, low=0.0)
        self._reset_own()

    def _reset_own(self):
        self._v = 0.0

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent ``dF/du`` [N/m] (the velocity tangent is ``c``)."""
        F, K = self._inner.trial(u, v)
        F += self.c * v
        self._set_trial(u, v, F)
        return F, K

    def _commit(self) -> None:
        W0 = self._inner.work
        D0 = self._inner.dissipated_energy
        self._inner.commit()
        dvisc = self.c * 0.5 * (self._v + self._tv) * (self._tu - self._u)
        self._W += self._inner.work - W0 + dvisc
        self._D += self._inner.dissipated_energy - D0 + dvisc
        self._v = self._tv


class PinningStiffness(_Effect):
    """A spring in parallel that engages after a clearance: ``k_p sign(u) max(|u| - delta, 0)``.

    Parameters
    ----------
    inner : joint element
    k_p : float, keyword-only
        Pinning stiffness [N/m], ``>= 0``.
    delta : float, keyword-only
        Clearance [m], ``>= 0`` (0: residual stiffness from the start, visible after
        macroslip; > 0: bolt shank bearing on the hole).
    """

    effect = "pinning_stiffness"
    parameter_names = ("k_p", "delta")

    def __init__(self, inner, *, k_p: float, delta: float = 0.0):
        super().__init__(inner)
        self.k_p = check_scalar("k_p", k_p, low=0.0)
        self.delta = check_scalar("delta", delta, low=0.0)

    def _spring(self, u: float) -> tuple[float, float, float]:
        e = abs(u) - self.delta
        if e <= 0.0:
            return 0.0, 0.0, 0.0
        return math.copysign(self.k_p * e, u), self.k_p, 0.5 * self.k_p * e * e

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        f, k, _ = self._spring(u)
        self._set_trial(u, v, F + f)
        return F + f, K + k

    def _commit(self) -> None:
        self._inner.commit()
        self._W = self._inner.work + self._spring(self._tu)[2]
        self._D = self._inner.dissipated_energy


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
    parameter_names = ("gap",)

    def __init__(self, inner, *, gap: float):
        super().__init__(inner)
        self.gap = check_scalar("gap", gap, low=0.0)
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


class SlipDegradation(_Effect):
    """Joint capacity decaying with the energy it has dissipated: ``F = lambda F_j``.

    ``lambda = exp(-rate * D_j)`` with ``D_j`` the wrapped joint's dissipated energy [J], updated
    once per committed step (so a trial uses the committed ``lambda``). Scaling the whole
    slider density by ``lambda`` scales both ``Fs`` and ``KT`` (loss of contact through wear or
    preload loss), so later cycles of a constant-amplitude test carry smaller forces.

    Parameters
    ----------
    inner : joint element
    rate : float, keyword-only
        Decay rate [1/J], ``>= 0``.

    Notes
    -----
    Energy: the work of a step is ``lambda dW_j``; the stored energy is ``lambda E_j``; the
    energy released when ``lambda`` drops, ``(lambda_old - lambda_new) E_j``, counts as
    dissipated.
    """

    effect = "slip_degradation"
    parameter_names = ("rate",)

    def __init__(self, inner, *, rate: float):
        super().__init__(inner)
        self.rate = check_scalar("rate", rate, low=0.0)
        self._reset_own()

    def _reset_own(self):
        self._lam = 1.0

    @property
    def capacity_factor(self) -> float:
        """Committed ``lambda`` in (0, 1]."""
        return self._lam

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        self._set_trial(u, v, self._lam * F)
        return self._lam * F, self._lam * K

    def _commit(self) -> None:
        inner = self._inner
        W0 = inner.work
        inner.commit()
        lam_old = self._lam
        self._lam = math.exp(-self.rate * inner.dissipated_energy)
        self._W += lam_old * (inner.work - W0)
        self._D = self._W - self._lam * inner.stored_energy


class AsymmetricSlip(_Effect):
    """Different slip capacity forward and back: ``F = (1 + a) F_j`` for ``F_j > 0``,
    ``(1 - a) F_j`` for ``F_j < 0``.

    Parameters
    ----------
    inner : joint element
    asymmetry : float, keyword-only
        ``a`` [-], in ``(-1, 1)``; macroslip forces are ``Fs (1 + a)`` and ``-Fs (1 - a)``.

    Notes
    -----
    The work is exact: a step in which the joint force changes sign is split at the zero.
    The stored energy is taken as ``(1 +- a) E_j`` with the sign of the committed force, and
    the dissipation as work minus stored energy; over a closed cycle it equals the loop area.
    """

    effect = "asymmetric_slip"
    parameter_names = ("asymmetry",)

    def __init__(self, inner, *, asymmetry: float):
        super().__init__(inner)
        self.asymmetry = check_scalar("asymmetry", asymmetry, low=-1.0, high=1.0,
                                      low_open=True, high_open=True)

    def _factor(self, F: float) -> float:
        return 1.0 + self.asymmetry if F > 0.0 else 1.0 - self.asymmetry

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        f = self._factor(F)
        self._set_trial(u, v, f * F)
        return f * F, f * K

    def _commit(self) -> None:
        """Commit, splitting the step where the joint force changes sign."""
        inner = self._inner
        u1 = float(self._tu)
        F0 = inner.force
        F1, _ = inner.trial(u1, self._tv)
        W0 = inner.work
        if F0 * F1 < 0.0:
            x = _find_zero(lambda y: inner.trial(y, self._tv), self._u, F0, u1, F1)
            inner.trial(x, self._tv)
            inner.commit()
            W_mid = inner.work
            self._W += self._factor(F0) * (W_mid - W0)
            inner.trial(u1, self._tv)
            inner.commit()
            self._W += self._factor(F1) * (inner.work - W_mid)
        else:
            inner.commit()
            Fm = F1 if F1 != 0.0 else F0
            self._W += self._factor(Fm) * (inner.work - W0)
        self._D = self._W - self._factor(inner.force) * inner.stored_energy


EFFECTS = {
    cls.effect: cls
    for cls in (ViscousDamping, PinningStiffness, Backlash, SlipDegradation, AsymmetricSlip)
}
"""The effect library by name (the names users and reports refer to)."""


def make_effect(name: str, inner, **parameters: float):
    """Wrap ``inner`` in the effect called ``name`` with the given parameters.

    ``parameters`` must be exactly the effect's parameter names (``ViscousDamping``: ``c``;
    ``PinningStiffness``: ``k_p``, ``delta``; ``Backlash``: ``gap``; ``SlipDegradation``:
    ``rate``; ``AsymmetricSlip``: ``asymmetry``); unknown names raise ``ValueError``.
    """
    if name not in EFFECTS:
        raise ValueError(f"unknown effect {name!r}; known effects are {sorted(EFFECTS)}")
    cls = EFFECTS[name]
    unknown = set(parameters) - set(cls.parameter_names)
    if unknown:
        raise ValueError(f"effect {name!r} takes parameters {list(cls.parameter_names)}, "
                         f"not {sorted(unknown)}")
    sig = inspect.signature(cls.__init__).parameters
    missing = [p for p in cls.parameter_names
               if sig[p].default is inspect.Parameter.empty and p not in parameters]
    if missing:
        raise ValueError(f"effect {name!r} needs parameter(s) {missing}")
    return cls(inner, **parameters)


def base_joint(element):
    """The innermost element below any stack of effects."""
    while isinstance(element, _Effect):
        element = element.inner
    return element
