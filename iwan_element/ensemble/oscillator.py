"""A single-mode structure with an Iwan joint: the closed-form f(X), zeta(X) and a transient run.

The structure is one mass ``m`` [kg] on a linear spring ``K_inf`` [N/m] in parallel with the
joint and a viscous dashpot (docs/equations.md section 7, modal Iwan, in physical units)::

    m x'' + c x' + K_inf x + F_J(x) = F0 sin(2 pi f t),   c = 2 zeta0 w0 m,
    w0^2 = (K_inf + KT) / m.

At displacement amplitude ``X`` (single-mode equivalent linearisation, docs/equations.md section 7,
secant stiffness paper eq. 24, joint dissipation paper eq. 17; evaluated by
:func:`iwan_element.modal_iwan_curve` with ``floor="dashpot"``)::

    w(X)^2  = (K_inf + K_sec(X)) / m
    zeta(X) = zeta0 w0 / w(X) + D(X) / (2 pi m w(X)^2 X^2)

(the dashpot dissipates ``pi c w X^2`` per cycle, hence ``zeta0 w0 / w``; docs/equations.md
section 7 writes ``zeta0`` for the same floor at ``w ~ w0``). :func:`peak_response` integrates
the equation of motion with the exact :class:`~iwan_element.IwanJoint` (average-acceleration
Newmark, Newton iterations with the joint's consistent tangent, one commit per accepted step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..base.validation import check_int, check_scalar, finite_array
from ..core.joint import IwanJoint
from ..core.modal import modal_iwan_curve
from ..core.parameters import IwanParameters

__all__ = ["SingleModeSystem", "modal_curve", "peak_response"]


@dataclass(frozen=True)
class SingleModeSystem:
    """Mass, parallel linear stiffness and viscous floor of a single-mode jointed structure.

    Parameters
    ----------
    mass : float
        Modal mass [kg], ``> 0``.
    stiffness : float
        Linear stiffness in parallel with the joint, ``K_inf`` [N/m], ``>= 0`` (the stiffness
        left when the joint is in macroslip).
    zeta0 : float
        Viscous damping ratio of the linearised system at ``w0`` [-], ``0 <= zeta0 < 1``.
    """

    mass: float
    stiffness: float
    zeta0: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "mass", check_scalar("mass", self.mass, low=0.0, low_open=True))
        object.__setattr__(self, "stiffness", check_scalar("stiffness", self.stiffness, low=0.0))
        object.__setattr__(
            self, "zeta0", check_scalar("zeta0", self.zeta0, low=0.0, high=1.0, high_open=True)
        )

    def linear_frequency(self, joint: IwanParameters) -> float:
        """``f0 = w0 / 2 pi`` with the joint at ``KT`` [Hz]."""
        return math.sqrt((self.stiffness + joint.KT) / self.mass) / (2.0 * math.pi)


def modal_curve(
    joint: IwanParameters, system: SingleModeSystem, amplitude, *, stiffness: str = "secant"
) -> tuple[float | NDArray[np.float64], float | NDArray[np.float64]]:
    """Closed-form frequency [Hz] and damping ratio [-] at displacement amplitudes [m].

    :func:`iwan_element.modal_iwan_curve` with the system's mass, ``K_inf`` and a fixed
    dashpot (``floor="dashpot"``, the damping :func:`peak_response` integrates).

    Parameters
    ----------
    joint : IwanParameters
    system : SingleModeSystem
    amplitude : array_like, shape (n,)
        Displacement amplitudes ``X`` [m], ``> 0``.
    stiffness : {"secant", "harmonic"}, keyword-only
        Secant (QSMA, docs/equations.md section 7) or first-harmonic stiffness (what a ring-down
        measures).

    Returns
    -------
    frequency, damping_ratio : ndarray, shape (n,)
    """
    X = finite_array("amplitude", amplitude)
    if np.any(X <= 0):
        raise ValueError("amplitude must be > 0 [m]")
    if not isinstance(system, SingleModeSystem):
        raise ValueError(f"system must be a SingleModeSystem, got {type(system).__name__}")
    return modal_iwan_curve(
        X,
        joint,
        K_inf=system.stiffness,
        zeta0=system.zeta0,
        mass=system.mass,
        stiffness=stiffness,
        floor="dashpot",
    )


def peak_response(
    joint: IwanParameters,
    system: SingleModeSystem,
    *,
    force: float,
    frequency: float | None = None,
    cycles: int = 30,
    steps_per_period: int = 64,
    return_history: bool = False,
) -> float | tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """Peak displacement [m] of the single-mode system driven from rest by ``F0 sin(2 pi f t)``.

    Average-acceleration Newmark (unconditionally stable, no numerical damping) with Newton
    iterations on the exact Iwan joint; the joint is committed once per converged step.

    Parameters
    ----------
    joint : IwanParameters
    system : SingleModeSystem
    force : float, keyword-only
        Force amplitude ``F0`` [N], ``> 0``.
    frequency : float, optional, keyword-only
        Forcing frequency [Hz], ``> 0``; default the linear frequency ``f0``.
    cycles : int, keyword-only
        Forcing periods simulated, ``>= 1``.
    steps_per_period : int, keyword-only
        Time steps per forcing period, ``>= 16``.
    return_history : bool, keyword-only
        Also return ``(t, x)``.

    Returns
    -------
    float, or (float, ndarray, ndarray) with ``return_history=True``
    """
    F0 = check_scalar("force", force, low=0.0, low_open=True)
    f = (
        system.linear_frequency(joint)
        if frequency is None
        else check_scalar("frequency", frequency, low=0.0, low_open=True)
    )
    cycles = check_int("cycles", cycles, 1)
    steps_per_period = check_int("steps_per_period", steps_per_period, 16)
    w = 2.0 * math.pi * f
    t, xs = _integrate(
        joint,
        system,
        h=1.0 / (f * steps_per_period),
        n=cycles * steps_per_period,
        load=lambda t_: F0 * math.sin(w * t_),
    )
    peak = float(np.max(np.abs(xs)))
    return (peak, t, xs) if return_history else peak


def _integrate(joint, system, *, h, n, load, x0=0.0):
    """Average-acceleration Newmark with Newton on the joint; returns ``(t, x)``.

    ``x0 > 0`` starts from rest at ``x0`` with the joint loaded along its backbone (a free
    decay, used by the tests against :func:`iwan_element.modal_ringdown`).
    """
    m, k = system.mass, system.stiffness
    c = 2.0 * system.zeta0 * math.sqrt((k + joint.KT) * m)
    j = IwanJoint(joint)
    x, v = x0, 0.0
    if x0:
        F, _ = j.trial(x0)  # loaded monotonically to x0 (backbone)
        j.commit()
    else:
        F = 0.0
    a = (load(0.0) - k * x - F) / m
    xs = np.empty(n + 1)
    xs[0] = x
    a0, a1 = 4.0 / (h * h), 2.0 / h  # Newmark gamma = 1/2, beta = 1/4
    for i in range(1, n + 1):
        p = load(i * h)
        xn = x + h * v + 0.25 * h * h * a  # predictor
        for _ in range(50):
            an = a0 * (xn - x) - 4.0 / h * v - a
            vn = v + 0.5 * h * (a + an)
            FJ, KJ = j.trial(xn)
            r = p - m * an - c * vn - k * xn - FJ
            if abs(r) <= 1e-11 * (abs(p) + abs(m * an) + abs(k * xn) + abs(FJ)) + 1e-300:
                break
            xn += r / (m * a0 + c * a1 + k + KJ)
        else:
            raise RuntimeError(f"Newton did not converge at step {i} (residual {r:.3g} N)")
        j.commit()
        x, v, a = xn, vn, an
        xs[i] = x
    return np.arange(n + 1) * h, xs
