"""The interface's joints condensed onto their slips: Newton's method on ``m`` unknowns.

In a time step of an implicit integrator, a structure that is linear but for Iwan elements
on its slip coordinates ``s`` reduces exactly to ``m`` equations in the slips (the host's
step, :mod:`iwan_element.models.simulation.newton`, derives them):

    g(s) = s - s_free + S (F(s) - KT s) = 0,

with ``S`` the structure's flexibility at the slips with the stuck springs ``KT`` in it (the
``m x m`` block of the inverse of the stuck iteration matrix) and ``s_free`` the slips the step
would reach with every joint held at its stuck stiffness. Newton's method with the joints'
consistent tangents ``K(s)`` (the derivative of the exact force the reversal-stack walk gives,
:meth:`~iwan_element.core.joint_bank.IwanJointBank.trial`; J. C. Simo and T. J. R. Hughes,
*Computational Inelasticity*, Springer 1998, ch. 1-3, for the idea in plasticity) solves

    (I + S diag(K(s) - KT)) ds = -g(s),

an ``m x m`` system per iteration, so a Jacobian update costs that, not the whole model
(docs/transient_cost.md). The forces are the same law as the symbolic expression Exudyn
evaluates (:mod:`.symbolic_law`): the same committed state, the same walk.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["condensed_slips"]


@njit(cache=True)
def _newton_update(s, s_free, S, KT, F, K):
    """One Newton update of ``g(s) = 0`` in place (module docstring); returns the largest
    force change ``max |ds_i| KT_i`` [N].
    """
    m = s.size
    g = s - s_free + S @ (F - KT * s)
    J = S * (K - KT).reshape(1, m)
    for i in range(m):
        J[i, i] += 1.0
    ds = np.linalg.solve(J, g)
    s -= ds
    return np.max(np.abs(ds) * KT)


def condensed_slips(
    bank, s_free, S, *, ftol: float, max_iter: int = 30
) -> tuple[np.ndarray, np.ndarray, int, bool]:
    """Slips ``s`` [m] of the points of ``bank`` in a linear structure condensed onto them:
    ``s - s_free + S (F(s) - KT s) = 0`` (module docstring), by Newton's method with the
    consistent tangents, from ``s_free``.

    Parameters
    ----------
    bank : IwanJointBank
        The points' committed state (not changed).
    s_free : ndarray, shape (m,)
        The slips with every point held at its stuck stiffness ``KT`` [m].
    S : ndarray, shape (m, m)
        The structure's flexibility at the slips with the stuck springs in it [m/N].
    ftol : float, keyword-only
        Stop when no point's force changes by more than ``ftol`` [N] in an iteration
        (``|ds_i| KT_i``).
    max_iter : int, keyword-only
        Most iterations.

    Returns
    -------
    (s, F, iterations, converged)
        The slips [m], the points' forces there [N], the iterations taken and whether
        ``ftol`` was met.
    """
    s = np.array(s_free, dtype=float)
    s_free = np.ascontiguousarray(s_free, dtype=float)
    F, K = np.empty_like(s), np.empty_like(s)
    for it in range(1, max_iter + 1):
        bank.trial(s, F, K)
        if _newton_update(s, s_free, S, bank.KT, F, K) <= ftol:
            bank.trial(s, F, K)
            return s, F, it, True
    bank.trial(s, F, K)
    return s, F, max_iter, False
