"""Slip degradation (wear): slip capacity falls with the energy the joint has dissipated.

Physics: fretting wear and the loss of preload it causes lower the friction capacity of the
contact as energy is dissipated in it, while the elastic stiffness of the stuck contact
(set by the clamped geometry) stays. Archard-type wear makes the worn volume proportional to
the frictional work, so the capacity is taken as ``lambda(D) = exp(-rate D)`` times the
original, with ``D`` the energy dissipated by the joint so far [J]. Every slider's threshold
is ``lambda phi_i``; its stiffness ``k_i`` is unchanged, so ``KT`` stays and ``Fs`` becomes
``lambda Fs``. A slider stretched beyond its shrunken threshold slips back to it at the
commit (the elastic energy released is dissipated).
"""
from __future__ import annotations

import math

import numpy as np

from ._base import ParamSpec
from ._sliders import _SliderEffect

__all__ = ["SlipDegradation"]

_MAX_ITER = 80
_LAM_TOL = 1e-14          # capacity change [-] at which the run's fixed point is accepted
_SHORT_RUN = 8            # runs of fewer steps go through the per-sample loop (cheaper there)


def _run_fixed_point(x0, xp0, lam0, rate, phi, k, step, D_in, Wb0, D_in0=None):
    """One monotone run of the correction bank, all samples at once.

    In the coordinate of the motion (``x``: modified sliders, ``xp``: plain sliders) a step
    ``s_j > 0`` maps every modified slider by ``x_j = clip(x_{j-1} + s_j, -c_j, min(c_{j-1},
    c_j))`` with ``c_j = lambda_j phi`` (stick or slide at the capacity before the step, then
    clip to the shrunken capacity), which for a non-increasing ``lambda`` composes to
    ``x_j = min(delta_j + max(x_0, max_{i<=j}(-c_i - delta_i)), c_j)`` (``delta``: travel since
    the run started). The capacities depend on the energy dissipated up to each step, which
    depends on the capacities before it: the run's ``lambda_j`` are found by fixed-point
    iteration (causal, so it converges; geometrically at the small capacity changes of one
    run). Returns ``None`` when ``lambda`` is not non-increasing or does not converge, else
    ``(force (modified - plain) per sample in the motion's coordinate, x_end, xp_end,
    lambda_end, Wb_end, force after the clip)``.
    """
    delta = np.cumsum(step)
    D_in0 = D_in[0] if D_in0 is None else D_in0
    # plain bank: fixed thresholds phi
    Xp = np.minimum(xp0[None, :] + delta[:, None], phi[None, :])
    Xp_prev = np.vstack([xp0[None, :], Xp[:-1]])
    wp = (0.5 * (Xp ** 2 - Xp_prev ** 2)
          + phi[None, :] * np.maximum(Xp_prev + step[:, None] - phi[None, :], 0.0)) @ k
    Fp = Xp @ k
    G = D_in - (np.cumsum(wp) - 0.5 * (Xp ** 2) @ k) + Wb0
    # start from the capacities the wrapped joint's own dissipation would give (the bank's
    # correction changes them by its discretisation error and the effect's feedback only)
    lam = lam0 * np.exp(-rate * np.maximum(D_in - D_in0, 0.0))
    for _ in range(_MAX_ITER):
        c = lam[:, None] * phi[None, :]
        c_prev = np.vstack([lam0 * phi[None, :], c[:-1]])
        M = np.maximum.accumulate(-c - delta[:, None], axis=0)
        X = np.minimum(delta[:, None] + np.maximum(x0[None, :], M), c)
        X_prev = np.vstack([x0[None, :], X[:-1]])
        y = np.minimum(X_prev + step[:, None], c_prev)
        w = (0.5 * (y ** 2 - X_prev ** 2)
             + c_prev * np.maximum(X_prev + step[:, None] - c_prev, 0.0)) @ k
        D = G + np.cumsum(w) - 0.5 * (y ** 2) @ k
        lam_new = np.exp(-rate * np.maximum(D, 0.0))
        done = float(np.max(np.abs(lam_new - lam))) <= _LAM_TOL
        lam = lam_new
        if done:
            break
    else:
        return None
    if lam[0] > lam0 or np.any(np.diff(lam) > 0.0):
        return None
    Wb_end = Wb0 + float(np.sum(w)) - float(np.sum(wp))
    return y @ k - Fp, X[-1], Xp[-1], float(lam[-1]), Wb_end, X @ k - Fp


class SlipDegradation(_SliderEffect):
    """Slider thresholds ``lambda phi_i``, ``lambda = exp(-rate D)``, stiffness unchanged.

    Parameters
    ----------
    inner : IwanJoint or DiscreteIwan
        The joint that wears (a plain joint; put other effects around this).
    rate : float, keyword-only
        Decay rate of the slip capacity per dissipated energy [1/J], ``>= 0``.
    n_sliders : int, keyword-only
        Sliders of the correction bank.
    """

    effect = "slip_degradation"
    specs = (ParamSpec("rate", "1/J", "relative loss of slip capacity per joule dissipated",
                       fs_power=-1, ref="D_ref", fit_bounds=(0.0, 5.0), fit_starts=(0.0, 0.2)),)

    def __init__(self, inner, *, rate: float, n_sliders: int = 128):
        super().__init__(inner, n_sliders=n_sliders)
        self._set_parameters({"rate": rate})
        self._reset_own()

    def _reset_own(self):
        self._lam = 1.0
        super()._reset_own()

    @property
    def capacity_factor(self) -> float:
        """Committed ``lambda`` in (0, 1]."""
        return self._lam

    def _caps(self):
        c = self._lam * self._phi
        return c, c, c, c

    def _after_commit(self) -> None:
        self._after_commit_energy(self._inner.dissipated_energy)

    def _correction_energy(self, u: np.ndarray, D_inner) -> np.ndarray:
        """The per-sample rule of :meth:`_SliderEffect._correction_energy`, solved one
        monotone run at a time (see :func:`_run_fixed_point`); a run whose capacity does not
        fall monotonically (possible only through the bank's discretisation error in the
        energy) is stepped sample by sample with the reference loop."""
        D_inner = np.asarray(D_inner, float)
        out = np.empty(u.size)
        du = np.diff(u, prepend=0.0)
        nz = np.flatnonzero(du)
        if nz.size == 0:
            out[:] = 0.0
            return out
        out[:nz[0]] = 0.0
        sgn = np.sign(du[nz])
        cut = np.flatnonzero(np.diff(sgn)) + 1
        n, k = self._n, self._k[:self._n]
        for seg in np.split(np.arange(nz.size), cut):
            idx = nz[seg]
            a = idx[0]
            b = nz[seg[-1] + 1] if seg[-1] + 1 < nz.size else u.size
            d = float(sgn[seg[0]])
            res = None
            if idx.size >= _SHORT_RUN:
                res = _run_fixed_point(d * self._e[:n], d * self._e[n:], self._lam, self.rate,
                                       self._phi, k, np.abs(du[idx]), D_inner[idx], self._Wb,
                                       D_inner[a - 1] if a > 0 else 0.0)
            if res is None:                      # short run or no monotone fixed point:
                # the reference, sample by sample (flags of the other direction: irrelevant)
                self._slip = np.zeros(2 * n)
                out[a:b] = super()._correction_energy(u[a:b], D_inner[a:b], prev=u[a] - du[a])
                continue
            F_run, x_end, xp_end, lam_end, Wb_end, F_post = res
            # samples without motion hold the committed (clipped) state's force
            last = np.searchsorted(idx, np.arange(a, b), side="right") - 1
            out[a:b] = d * F_post[last]
            out[idx] = d * F_run
            self._e = d * np.concatenate([x_end, xp_end])
            self._lam, self._Wb = lam_end, Wb_end
            self._refresh_caps()
        return out

    def _after_commit_energy(self, D_inner: float) -> None:
        """Update ``lambda`` from the joint's dissipated energy and clip the stretches."""
        D = D_inner + self._Wb - self._stored(self._e)
        self._lam = math.exp(-self.rate * max(D, 0.0))
        n = self._n
        cap = self._lam * self._phi
        e = self._e[:n]
        np.minimum(e, cap, out=e)
        np.maximum(e, -cap, out=e)
        self._refresh_caps()
