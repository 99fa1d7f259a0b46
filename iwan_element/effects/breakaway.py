"""Break-away (static above kinetic friction): a stuck slider must reach a higher force to
start sliding than it carries while sliding.

Physics: the classical static/kinetic friction law (Coulomb-Morin; the stick-slip
literature, e.g. Armstrong-Helouvry, Dupont and Canudas de Wit, Automatica 30, 1994, the
"break-away force"). Every slider of the joint (slip displacement ``phi``, REFERENCE.md
sec. 2), once stuck (at the start and after every reversal of its motion), holds until its
stretch reaches ``r phi`` (static), then slides at stretch ``phi`` (kinetic) until its
motion reverses. In a loop this is a force peak of up to ``r`` times the sliding force just
after the joint starts to slide in a new direction, the signature the ARTS friction-damper
records show (1.2-2.5 x the sliding force after each reversal). The drop from the static to
the kinetic level is instantaneous in this rate-independent law; a real test rig answers
that drop with its own structural ringing (40-50 Hz on the damper rig), which is a property
of the rig, not of the joint, and is removed before fitting (see :func:`iwan_element.diagnose`
``lowpass``).

Exact evaluation on the continuous density (no slider bank). The sliders' state is a
function of ``phi`` that is piecewise linear, ``e(phi) = s phi + c`` with ``s`` in
``{-1, 0, 1}``, on intervals of ``phi``: sliders that slide sit at ``e = +-phi``, stuck ones
keep ``e`` plus the travel since. In a monotone run of travel ``delta`` (direction ``d``,
stretches taken along ``d``) a stuck slider of an interval breaks when
``s phi + c + delta > r phi``, i.e. for ``phi < (c + delta) / (r - s)``: the broken sliders of
every interval are its lower part, bounded by a point that moves continuously with ``delta``
and ``r``. The force is then the density's moments over these pieces (REFERENCE.md sec. 2:
``rho = R phi^chi`` on ``(0, phi_max)`` plus the spike ``S`` at ``phi_max``),

``F = int_broken rho phi dphi + int_stuck rho (s phi + c + delta) dphi``,

in closed form, so the force, and the misfit of a fit, are continuous in ``r`` (a bank of
discrete sliders makes them a staircase: each slider breaks at one sample or the next). A
wrapped :class:`~iwan_element.core.discrete.DiscreteIwan` is handled the same way with its
sliders as point masses (the spike ``S`` is one). At ``r = 1`` these rules are the Masing
rules of the plain joint; the element adds ``F(r) - F(1)`` (both from the same pieces) to the
wrapped joint's own force, so it reduces exactly to that joint at ``r = 1``. Checked against
an independent plain-Python slider bank, to which a dense bank converges
(``tests/test_breakaway.py``).
"""
from __future__ import annotations

import numpy as np

from ..core.discrete import DiscreteIwan
from ..core.parameters import IwanParameters
from ._base import ParamSpec, _Effect, _require_plain_joint

__all__ = ["BreakAway"]


class _Pieces:
    """Slider states on intervals of ``phi`` for a set of banks (here: ratio ``r`` and the
    reference ``1``), each bank weighted by a sign; all arrays have one row per piece.

    Rows: ``a, b`` interval [m] (``a == b`` for a point mass of stiffness ``w`` [N/m]),
    ``s, c`` the state ``e = s phi + c`` [m], ``slide`` (+1/-1 sliding that way, 0 stuck),
    ``rat`` the bank's ratio, ``sg`` its sign. Continuous rows carry the density
    ``rho = C / pm (phi / pm)^(p - 1)`` (``C = (chi + 1) KT / (1 + beta)``, ``p = chi + 1``).
    """

    def __init__(self, params: IwanParameters, atoms, ratios, signs):
        self.pm, self.p = params.phi_max, params.chi + 1.0
        self.C = self.p * params.K_slider
        rows = []
        for r, sg in zip(ratios, signs):
            if atoms is None:                        # continuous part + the spike S
                rows.append((0.0, self.pm, 0.0, r, sg))
                if params.beta > 0.0:
                    rows.append((self.pm, self.pm, params.KT - params.K_slider, r, sg))
            else:
                rows.extend((ph, ph, k, r, sg) for k, ph in zip(*atoms))
        a, b, w, rat, sg = (np.array(x, float) for x in zip(*rows))
        z = np.zeros(a.size)
        self.state = {"a": a, "b": b, "w": w, "rat": rat, "sg": sg, "s": z, "c": z.copy(),
                      "slide": z.copy()}
        self._tot = self._last = None

    @property
    def totals(self):
        """``int rho phi^k`` over every row, ``k = 0, 1, 2`` (cached per state)."""
        if self._tot is None:
            st = self.state
            self._tot = self._moments(st, st["b"], True, 3)
        return self._tot

    # ---- moments of the density over [a, x] (x may be a 2-D array of limits)
    def _moments(self, st, x, broken, n):
        """``int rho phi^k``, ``k < n``, over the broken part ``[a, x]`` of every row (point
        masses: all of their weight where ``broken``)."""
        atom = st["w"] > 0.0
        a = st["a"]
        xr = np.where(atom, a, x) / self.pm
        ar = a / self.pm
        px, pa = xr ** self.p, ar ** self.p
        out = []
        for k in range(n):
            cont = self.C * self.pm ** k * (px - pa) / (self.p + k)
            out.append(np.where(atom, st["w"] * a ** k * broken, cont))
            px, pa = px * xr, pa * ar
        return out

    def _limit(self, st, d, delta):
        """Broken part of each row after a travel ``delta`` (>= 0, any shape ending in the
        rows) in direction ``d``: ``(x, broken, s_d, c_d)`` with ``x`` the clipped limit
        and ``broken`` for point masses."""
        s_d, c_d = d * st["s"], d * st["c"]
        num = c_d + delta
        den = st["rat"] - s_d
        with np.errstate(divide="ignore", invalid="ignore"):
            raw = np.where(den > 0.0, num / np.where(den > 0.0, den, 1.0),
                           np.where(num > 0.0, np.inf, -np.inf))
        raw = np.where(st["slide"] == d, np.inf, raw)
        return np.clip(raw, st["a"], st["b"]), raw > st["a"], s_d, c_d, raw, den

    def force(self, d: float, delta):
        """Signed force of the banks (sum of ``sg`` x bank force) after a travel ``delta``
        [m] (scalar or 1-D array) from the current state in direction ``d``, and the
        tangent [N/m] (continuous part; a point mass breaking is a jump)."""
        st = self.state
        last = self._last
        if last is not None and np.ndim(delta) == 0 and last[0] == d and last[1] == delta:
            return last[7]               # the same step again (a wrapper re-trials to commit)
        dl = np.asarray(delta, float)[..., None]
        x, brk, s_d, c_d, raw, den = self._limit(st, d, dl)
        M0t, M1t = self.totals[:2]
        scalar = dl.ndim == 1
        if scalar:                       # one step (element route): kept for advance()
            Mb = self._moments(st, x, brk, 3)
        else:
            Mb = self._moments(st, x, brk, 2)
        M0b, M1b = Mb[:2]
        F = M1b + s_d * (M1t - M1b) + (c_d + dl) * (M0t - M0b)
        inside = (st["w"] == 0.0) & (raw > st["a"]) & (raw < st["b"]) & (den > 0.0)
        xs = np.where(inside, x, self.pm)
        rho = self.C / self.pm * (xs / self.pm) ** (self.p - 1.0)
        K = (M0t - M0b) - np.where(inside, rho * (st["rat"] - 1.0) * xs / np.where(
            den > 0.0, den, 1.0), 0.0)
        out = d * (F @ st["sg"]), K @ st["sg"]
        if scalar:
            self._last = (d, float(delta), x, brk, s_d, c_d, Mb, out)
        return out

    def advance(self, d: float, delta: float) -> float:
        """Move the state by a travel ``delta >= 0`` in direction ``d``; returns the signed
        work done on the banks [J] (exact: stick to ``r phi``, then slide at ``phi``)."""
        st = self.state
        last = self._last
        if last is not None and last[0] == d and last[1] == delta:
            x, brk, s_d, c_d, Mb = last[2:7]
        else:
            x, brk, s_d, c_d, _, _ = self._limit(st, d, delta)
            Mb = self._moments(st, x, brk, 3)
        M = self.totals
        Mu = [t - b_ for t, b_ in zip(M, Mb)]
        r = st["rat"]
        work_b = ((0.5 * r * r - r - 0.5 * s_d * s_d + s_d) * Mb[2]
                  + (delta + c_d * (1.0 - s_d)) * Mb[1] - 0.5 * c_d * c_d * Mb[0])
        work = np.where(st["slide"] == d, delta * M[1],
                        work_b + delta * (s_d * Mu[1] + c_d * Mu[0]) + 0.5 * delta ** 2 * Mu[0])
        atom = st["w"] > 0.0
        has_b = np.where(atom, brk, x > st["a"])
        has_u = np.where(atom, ~brk, x < st["b"])
        lo = {key: v[has_b] for key, v in st.items()}
        lo.update(b=np.where(atom, st["b"], x)[has_b], s=np.full(lo["a"].size, d),
                  c=np.zeros(lo["a"].size), slide=np.full(lo["a"].size, d))
        hi = {key: v[has_u] for key, v in st.items()}
        hi.update(a=np.where(atom, st["a"], x)[has_u], c=(st["c"] + d * delta)[has_u],
                  slide=np.zeros(hi["a"].size))
        # interleave (broken part first, then the stuck part of the same row): keeps order
        order = np.argsort(np.concatenate([np.flatnonzero(has_b) * 2,
                                           np.flatnonzero(has_u) * 2 + 1]), kind="stable")
        new = {key: np.concatenate([lo[key], hi[key]])[order] for key in st}
        self.state = _merge(new)
        self._tot = self._last = None
        return float(work @ st["sg"])

    def stored(self) -> float:
        """Signed elastic energy of the banks [J]: ``0.5 int rho e^2``."""
        st = self.state
        M = self.totals
        s, c = st["s"], st["c"]
        return 0.5 * float((s * s * M[2] + 2.0 * s * c * M[1] + c * c * M[0]) @ st["sg"])


def _merge(st: dict) -> dict:
    """Join neighbouring continuous rows with the same state and bank (keeps rows few)."""
    n = st["a"].size
    if n < 2:
        return st
    same = np.ones(n - 1, bool)
    for key in ("s", "c", "slide", "rat", "sg"):
        same &= st[key][1:] == st[key][:-1]
    same &= (st["w"][1:] == 0.0) & (st["w"][:-1] == 0.0) & (st["b"][:-1] == st["a"][1:])
    if not same.any():
        return st
    first = np.concatenate([[True], ~same])
    last = np.concatenate([~same, [True]])
    out = {key: v[first] for key, v in st.items()}
    out["b"] = st["b"][last]
    return out


class BreakAway(_Effect):
    """Static threshold ``r phi``, kinetic threshold ``phi`` on every slider of the joint.

    Parameters
    ----------
    inner : IwanJoint or DiscreteIwan
        The joint (a plain joint; put other effects around this). For a
        :class:`~iwan_element.core.discrete.DiscreteIwan` the effect acts on its own sliders.
    ratio : float, keyword-only
        Static over kinetic friction ``r`` [-], ``>= 1`` (1: no break-away peak).
    """

    effect = "breakaway"
    slider_level = True
    specs = (ParamSpec("ratio", "1", "static over kinetic slip threshold", lower=1.0,
                       fit_bounds=(1.0, 3.0), fit_starts=(1.0, 1.2, 1.5, 2.0)),)
    #: Ratios scanned for a start: the force changes only to second order in ``ratio - 1``
    #: near 1 (the static-kinetic jump and the shift of the break both scale with it), so a
    #: fit started at 1 has no gradient to follow.
    fit_scan = tuple(1.0 + 0.1 * k for k in range(21))
    needs_energy = False
    #: The spike's sliders break all at once: the force jumps, and whether they break in a
    #: half cycle is a yes/no event of the parameters (fits restart around their result).
    force_jumps = True

    def __init__(self, inner, *, ratio: float):
        super().__init__(inner)
        _require_plain_joint(inner, "break-away")
        self._set_parameters({"ratio": ratio})
        self._atoms = ((inner.slider_stiffness, inner.slider_slip)
                       if isinstance(inner, DiscreteIwan) else None)
        self._reset_own()

    def _new_pieces(self) -> _Pieces:
        return _Pieces(self._inner.params, self._atoms, (self.ratio, 1.0), (1.0, -1.0))

    def _reset_own(self):
        self._pieces = self._new_pieces()
        self._ub = 0.0                            # displacement of the committed state [m]
        self._dir = 1.0                           # direction of the last move
        self._Wb = 0.0                            # work of (ratio bank - reference bank) [J]
        self._last = None

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
        return int(self._pieces.state["a"].size)

    def correction_history(self, u, D_inner=None) -> np.ndarray:
        """Force ``F(ratio) - F(1)`` [N] along a displacement history ``u`` [m] from the
        virgin state (private state; this element is untouched): one vectorised evaluation
        per monotone run of ``u`` (breaking is monotone within a run, so this equals the
        step-by-step rule of :meth:`trial`/:meth:`commit`). ``D_inner`` is not used."""
        uu = np.asarray(u, float)
        pieces = self._new_pieces()
        out = np.zeros(uu.size)
        du = np.diff(uu, prepend=0.0)
        nz = np.flatnonzero(du)
        if nz.size == 0:
            return out
        sgn = np.sign(du[nz])
        starts = nz[np.flatnonzero(np.diff(sgn, prepend=0.0))]
        ends = np.append(starts[1:], uu.size)
        for a, b in zip(starts, ends):
            d = float(np.sign(du[a]))
            u_s = uu[a - 1] if a > 0 else 0.0
            delta = d * (uu[a:b] - u_s)
            out[a:b] = pieces.force(d, delta)[0]
            pieces.advance(d, float(delta[-1]))
        return out
