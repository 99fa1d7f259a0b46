"""Vectorised force evaluation of the Iwan joint over a fixed displacement history.

For a displacement-driven history the reversal points, and hence which Masing branch each
sample lies on, depend only on the displacements, not on the joint parameters. This module
finds that structure once (the compiled walk every exact element uses,
:func:`iwan_element.core.masing.reversal_structure`) and then evaluates the forces for any
parameter set with a few numpy operations:

* sample ``i`` lies on the branch that leaves the reversal sample ``a = anchor[i]``
  (``-1``: the virgin curve), so ``F[i] = F[a] + sign(u_i - u_a) 2 F_bb(|u_i - u_a|/2)``
  (paper eq. 13 and the corrected eq. 15) or ``F[i] = sign(u_i) F_bb(|u_i|)``;
* the anchors of the samples at nesting level ``L`` lie at level ``L - 1``, so the forces are
  accumulated level by level: ``F = G; F[level L] += F[anchor[level L]]`` for ``L = 1, 2, ...``.

The per-sample backbone terms ``G`` are the only parameter-dependent part; the backbone is
``Fs f(x/phi_max; chi, beta)`` (paper eq. 12), so the force is linear in ``Fs`` at fixed
``(phi_max, chi, beta)``. Only the samples that are fitted and their chains of anchors are
kept, so a decimated fit still uses the exact reversal points of the full record.

Used by :mod:`iwan_element.identify.loops.fit`; verified against ``IwanJoint.force_history``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .closed_form import backbone
from .masing import reversal_structure
from .parameters import IwanParameters

__all__: list[str] = []

#: The package's one reversal tolerance, relative to the displacement scale (``phi_max`` in
#: :class:`~iwan_element.IwanJoint`, the largest |u| of a record in the fits): smaller
#: excursions from a turning point are not reversals.
REVERSAL_TOL = 1e-12


def unit_params(phi_max: float, chi: float, beta: float) -> IwanParameters:
    """Parameters with ``Fs = 1`` and the given ``phi_max`` [m] (paper eq. 11 solved for KT)."""
    c = beta + (chi + 1.0) / (chi + 2.0)
    return IwanParameters(1.0, (1.0 + beta) / (phi_max * c), chi, beta)


@njit(cache=True)
def _levels(anchor):
    """Nesting level of every sample: one more than its anchor's (anchors precede samples)."""
    level = np.zeros(anchor.size, np.int64)
    for i in range(anchor.size):
        if anchor[i] >= 0:
            level[i] = level[anchor[i]] + 1
    return level


def _structure(u: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """Anchor index (``-1`` = virgin curve) and nesting level of every sample of ``u``."""
    anchor, _ = reversal_structure(u, tol)
    return anchor, _levels(anchor).astype(np.intp)


class History:
    """Reversal structure of one displacement history, restricted to the samples needed.

    Parameters
    ----------
    u : ndarray, shape (n,)
        Displacement history [m], starting from the virgin state at ``u = 0``.
    keep : ndarray of int, optional
        Sample indices whose forces are wanted (default: all). Their anchors are kept too.
    tol : float
        Absolute reversal tolerance [m] (see ``IwanJoint(reversal_tol=...)``).

    Attributes
    ----------
    x : ndarray
        Backbone argument of every kept sample [m]: ``|u_i - u_a|/2`` on a branch, ``|u_i|``
        on the virgin curve.
    x_max : float
        Largest backbone argument among the requested samples [m]; the record reaches
        macroslip for a parameter set iff ``x_max > phi_max``.
    """

    def __init__(self, u: np.ndarray, *, keep: np.ndarray | None = None, tol: float = 0.0):
        anchor, level = _structure(u, tol)
        n = len(u)
        want = np.arange(n) if keep is None else np.unique(np.asarray(keep, dtype=np.intp))
        need = np.zeros(n, dtype=bool)
        need[want] = True
        frontier = anchor[want]
        while frontier.size:  # add the chains of anchors
            frontier = np.unique(frontier[frontier >= 0])
            frontier = frontier[~need[frontier]]
            need[frontier] = True
            frontier = anchor[frontier]
        idx = np.flatnonzero(need)  # sorted: anchors precede their samples
        pos = np.full(n, -1, dtype=np.intp)
        pos[idx] = np.arange(idx.size)
        a_full = anchor[idx]
        self.index = idx
        self.out = pos[want]  # where the requested samples sit in idx
        a = np.where(a_full >= 0, pos[np.maximum(a_full, 0)], -1)
        uu = u[idx]
        branch = a >= 0
        dx = np.where(branch, uu - uu[np.maximum(a, 0)], uu)
        self.x = np.where(branch, 0.5 * np.abs(dx), np.abs(dx))
        self.mult = np.where(branch, 2.0, 1.0) * np.where(dx >= 0.0, 1.0, -1.0)
        lev = level[idx]
        order = np.argsort(lev, kind="stable")
        bounds = np.searchsorted(lev[order], np.arange(1, lev.max() + 2 if lev.size else 1))
        self.levels = [
            (order[bounds[k] : bounds[k + 1]], a[order[bounds[k] : bounds[k + 1]]])
            for k in range(len(bounds) - 1)
            if bounds[k + 1] > bounds[k]
        ]
        self.x_max = float(self.x[self.out].max()) if self.out.size else 0.0
        self.depth = int(lev.max()) if lev.size else 0

    def accumulate(self, g: np.ndarray) -> np.ndarray:
        """Forces of the requested samples from the per-sample branch terms ``g`` (kept order)."""
        F = g.copy()
        for sel, anc in self.levels:
            F[sel] += F[anc]
        return F[self.out]

    def forces(self, params: IwanParameters) -> np.ndarray:
        """Forces [N] at the requested samples (in the order of ``keep``) for ``params``."""
        return self.accumulate(self.mult * backbone(self.x, params))
