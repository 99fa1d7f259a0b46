"""Exact slider laws on the continuous Iwan density: the engine of the law effects.

Every slider of the joint (slip displacement ``phi``, docs/equations.md section 2) follows a
direction-dependent Coulomb-Morin law: once stuck (at the start and after every reversal of
its motion) it holds until its stretch reaches ``sigma_d phi`` (static threshold in the
direction ``d`` of motion), then slides at stretch ``kappa_d phi`` (kinetic) until its motion
reverses; ``sigma_d >= kappa_d > 0``. The plain joint is ``sigma = kappa = 1`` both ways (the
Masing rules); break-away is ``sigma = r``, ``kappa = 1``; direction-dependent slip is
``sigma_d = kappa_d = 1 +- a``; a break-away on an asymmetric contact is their product.

The sliders' state is a function of ``phi`` that is piecewise linear, ``e(phi) = s phi + c``,
on intervals of ``phi``: sliding sliders sit at ``e = d kappa_d phi``, stuck ones keep ``e``
plus the travel since. In a monotone run of travel ``delta`` (direction ``d``, stretches taken
along ``d``) a stuck slider of an interval breaks when ``s_d phi + c_d + delta > sigma_d phi``,
i.e. for ``phi < (c_d + delta) / (sigma_d - s_d)``: the broken sliders of every interval are its
lower part, bounded by a point that moves continuously with ``delta`` and the law. The force
is the density's moments over these pieces (``rho = R phi^chi`` on ``(0, phi_max)`` plus the
spike ``S`` at ``phi_max``),

``F = kappa_d int_broken rho phi dphi + int_stuck rho (s_d phi + c_d + delta) dphi``,

in closed form, so the force, and the misfit of a fit, are continuous in the law's
parameters (a bank of discrete sliders makes them a staircase). The state table is moved and
evaluated by compiled functions (:mod:`.law_kernel`). A
:class:`~iwan_element.core.discrete.DiscreteIwan` is handled the same way with its sliders as
point masses. Checked against independent plain-Python slider banks
(``tests/test_breakaway.py``, ``tests/test_effects.py``).

**Law effects compose.** :class:`LawEffect` is the element of one such law (an effect
defines its own factors, :meth:`LawEffect.own_law`). Wrapping another law effect, its
factors multiply those below (direction-dependent slip on a contact with break-away is
``sigma_d = r (1 +- a)``, ``kappa_d = 1 +- a``), and it adds the force of the product law's
bank minus that of the law below: each element of the chain is exact on its own and their
sum is the product law on the joint.
"""

from __future__ import annotations

import numpy as np

from ...core.discrete import DiscreteIwan
from ...core.parameters import IwanParameters
from ..base import Effect, require_plain_joint
from . import law_kernel as K

__all__: list[str] = []

#: The law of the plain joint: ``(sigma_up, sigma_down, kappa_up, kappa_down)``.
MASING = (1.0, 1.0, 1.0, 1.0)


class _Pieces:
    """Slider states on intervals of ``phi`` for a set of banks (each with its own law), each
    bank weighted by a sign: the state table of :mod:`.law_kernel` (one column per piece),
    moved and evaluated by its compiled functions.

    Rows: ``a, b`` interval [m] (``a == b`` for a point mass of stiffness ``w`` [N/m]),
    ``su, sd, ku, kd`` the bank's law (static and kinetic thresholds up and down, as multiples
    of ``phi``), ``sg`` its sign, ``s, c`` the state ``e = s phi + c`` [m], ``slide`` (+1/-1
    sliding that way, 0 stuck). Continuous rows carry the density
    ``rho = C / pm (phi / pm)^(p - 1)`` (``C = (chi + 1) KT / (1 + beta)``, ``p = chi + 1``).
    """

    def __init__(self, params: IwanParameters, atoms, laws, signs):
        self.pm, self.p = params.phi_max, params.chi + 1.0
        self.C = self.p * params.K_slider
        rows = []
        for law, sg in zip(laws, signs):
            if atoms is None:  # continuous part + the spike S
                rows.append((0.0, self.pm, 0.0, *law, sg))
                if params.beta > 0.0:
                    rows.append((self.pm, self.pm, params.KT - params.K_slider, *law, sg))
            else:
                rows.extend((ph, ph, k, *law, sg) for k, ph in zip(*atoms))
        st = np.zeros((K.N_ROWS, len(rows)))
        st[: K.S] = np.array(rows, float).T  # s, c, slide: 0 (stuck, unstretched)
        self.state = st
        # the last scalar step (d, delta, (force, tangent)), replayed when asked again
        self._last: tuple[float, float, tuple[float, float]] | None = None

    def force(self, d: float, delta):
        """Signed force of the banks (sum of ``sg`` x bank force) after a travel ``delta``
        [m] (scalar or 1-D array) from the current state in direction ``d``, and the
        tangent [N/m] (continuous part; a point mass breaking is a jump).
        """
        if np.ndim(delta) == 0:
            delta = float(delta)
            last = self._last
            if last is not None and last[0] == d and last[1] == delta:
                return last[2]  # the same step again (a wrapper re-trials to commit)
            F, Kt = K.law_force(self.state, float(d), np.array([delta]), self.pm, self.p, self.C)
            out = float(F[0]), float(Kt[0])
            self._last = (d, delta, out)
            return out
        return K.law_force(self.state, float(d), np.asarray(delta, float), self.pm, self.p, self.C)

    def advance(self, d: float, delta: float) -> float:
        """Move the state by a travel ``delta >= 0`` in direction ``d``; returns the signed
        work done on the banks [J] (exact: stick to ``sigma_d phi``, slide at
        ``kappa_d phi``).
        """
        self.state, work = K.law_advance(
            self.state, float(d), float(delta), self.pm, self.p, self.C
        )
        self._last = None
        return float(work)

    def stored(self) -> float:
        """Signed elastic energy of the banks [J]: ``0.5 int rho e^2``."""
        return float(K.law_stored(self.state, self.pm, self.p, self.C))


def law_history(pieces: _Pieces, u) -> np.ndarray:
    """Signed bank force along a displacement history ``u`` [m] from the state of ``pieces``
    (which is advanced): one evaluation per monotone run of ``u`` (breaking is monotone
    within a run, so this equals the step-by-step rule), compiled
    (:func:`.law_kernel.law_history`).
    """
    out, pieces.state = K.law_history(
        pieces.state, np.ascontiguousarray(u, dtype=float), pieces.pm, pieces.p, pieces.C
    )
    pieces._last = None
    return out


def _product(law, below) -> tuple:
    """Two laws on the same sliders: their threshold factors multiply."""
    return tuple(a * b for a, b in zip(law, below))


class LawEffect(Effect):
    """Element of a slider law (module docstring): wraps a plain joint or another law effect.

    Subclasses set :attr:`specs` and define :meth:`own_law`; their constructor stores the
    parameters (``_set_parameters``) and then calls ``_reset_own``.
    """

    structure = "slider"
    composable = True

    def __init__(self, inner):
        super().__init__(inner)
        joint = inner
        while isinstance(joint, LawEffect):
            joint = joint.inner
        require_plain_joint(joint, f"{self.effect} (a slider law)")
        self._joint = joint
        self._atoms = (
            (joint.slider_stiffness, joint.slider_slip) if isinstance(joint, DiscreteIwan) else None
        )

    def own_law(self) -> tuple:
        """``(sigma_up, sigma_down, kappa_up, kappa_down)`` of this effect alone [-]."""
        raise NotImplementedError

    def _below(self) -> tuple:
        """The law of the element this one wraps (Masing for the plain joint)."""
        return self._inner.law() if isinstance(self._inner, LawEffect) else MASING

    def law(self) -> tuple:
        """The law of this effect times every law effect below it."""
        return _product(self.own_law(), self._below())

    def _new_pieces(self) -> _Pieces:
        below = self._below()
        return _Pieces(
            self._joint.params, self._atoms, (_product(self.own_law(), below), below), (1.0, -1.0)
        )

    def _reset_own(self):
        self._pieces = self._new_pieces()
        self._ub = 0.0  # displacement of the committed state [m]
        self._dir = 1.0  # direction of the last move
        self._Wb = 0.0  # work of (this law - the law below) [J]

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m]."""
        F, K = self._inner.trial(u, v)
        du = float(u) - self._ub
        # no move: the committed force, with the tangent of going on in the last direction
        d = (1.0 if du > 0.0 else -1.0) if du != 0.0 else self._dir
        dF, dK = self._pieces.force(d, abs(du))
        self._set_trial(u, v, F + float(dF))
        return F + float(dF), K + float(dK)

    def _commit(self) -> None:
        inner = self._inner
        inner.commit()
        du = float(self._tu) - self._ub
        if du != 0.0:
            self._dir = 1.0 if du > 0.0 else -1.0
            self._Wb += self._pieces.advance(self._dir, abs(du))
        self._ub = float(self._tu)
        self._W = inner.work + self._Wb
        self._D = inner.dissipated_energy + self._Wb - self._pieces.stored()

    @property
    def n_pieces(self) -> int:
        """Number of ``phi`` intervals the committed state is kept on (both banks)."""
        return int(self._pieces.state.shape[1])

    def correction_history(self, u, D_inner=None) -> np.ndarray:
        """The element's force minus its inner element's [N] along a displacement history
        ``u`` [m] from the virgin state (private state; this element is untouched): one
        vectorised evaluation per monotone run of ``u`` (:func:`law_history`), equal to the
        step-by-step rule of :meth:`trial`/:meth:`commit`. ``D_inner`` is not used.
        """
        return law_history(self._new_pieces(), u)
