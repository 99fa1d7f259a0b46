"""Accepted slips of many marker pairs from a view of Exudyn's coordinates (post-step only).

Used by the interface and the symbolic connector route; never called in a force law.
"""

from __future__ import annotations

import exudyn as exu
import numpy as np

__all__ = ["SlipMap", "JOINT_CHECKS"]

_POSITION = exu.OutputVariableType.Position
_CURRENT = exu.ConfigurationType.Current


class SlipMap:
    """Accepted slips ``u = C q + c`` of all points from a view of the ODE2 coordinates.

    Exact for markers whose position is affine in the coordinates (node coordinates, point
    nodes, mass points, ANCF cable elements at their axis); checked at set-up by perturbing
    each coordinate alone and all of them jointly (:func:`_affine_position_row`). Points with
    other markers (rigid bodies off their reference point, flexible bodies on a floating
    frame, ANCF surface points) are read with ``GetMarkerOutput`` (post-step only).
    """

    def __init__(self, mbs, pairs, kind, axis, offsets):
        sd = mbs.systemData
        self.q = sd.GetODE2Coordinates(copy=False)
        self.pairs, self.kind, self.axis, self.offsets = pairs, kind, axis, offsets
        n = len(pairs)
        rows = [self._row(mbs, i) for i in range(n)]
        width = max(1, max(len(r[0]) for r in rows if r is not None) if any(rows) else 1)
        self.idx = np.zeros((n, width), dtype=np.intp)
        self.coef = np.zeros((n, width))
        self.c = np.zeros(n)
        self.generic = [i for i, r in enumerate(rows) if r is None]
        for i, r in enumerate(rows):
            if r is not None:
                k = len(r[0])
                self.idx[i, :k] = r[0]
                self.coef[i, :k] = r[1]
                self.c[i] = r[2]
        self.mbs = mbs

    def _row(self, mbs, i):
        m0, m1 = (int(m) for m in self.pairs[i])
        off = self.offsets[i]
        if self.kind == "coordinate":
            idx, coef = [], []
            for m, sgn in ((m0, -1.0), (m1, 1.0)):
                mk = mbs.GetMarker(m)
                node = int(mk["nodeNumber"])
                if mbs.GetNode(node)["nodeType"] != "PointGround":
                    idx.append(mbs.GetNodeODE2Index(node) + int(mk["coordinate"]))
                    coef.append(sgn)
            return idx, coef, -off
        return _affine_position_row(mbs, m0, m1, self.axis, off)

    def slips(self) -> np.ndarray:
        """Accepted slips ``u`` [m] of all points from the current coordinates."""
        u = (self.q[self.idx] * self.coef).sum(axis=1) + self.c
        if self.generic:
            self.marker_slips(u, self.generic)
        return u

    def marker_slips(self, u: np.ndarray, points) -> None:
        """Write into ``u`` the slips of ``points`` read from Exudyn's marker positions
        (pairs with no affine row; one ``GetMarkerOutput`` per marker).
        """
        a = np.asarray(self.axis, float)
        get = self.mbs.GetMarkerOutput
        for i in points:
            m0, m1 = self.pairs[i]
            u[i] = float(a @ (get(int(m1), _POSITION) - get(int(m0), _POSITION))) - self.offsets[i]


def _marker_coordinates(mbs, m):
    mk = mbs.GetMarker(m)
    sd = mbs.systemData
    if "bodyNumber" in mk:
        return list(sd.GetObjectLTGODE2(int(mk["bodyNumber"])))
    if "nodeNumber" in mk:
        return list(sd.GetNodeLTGODE2(int(mk["nodeNumber"])))
    return None


#: Joint perturbations of all coordinates a position row is checked at (after the
#: one-coordinate differences gave its coefficients): a map that is affine in each coordinate
#: alone but not jointly (a modal coordinate times the rotation of a floating frame, as in a
#: reduced flexible body, ``p = p_ref + A(theta) (x + Phi q)``) fails here.
JOINT_CHECKS = 3


def _affine_position_row(mbs, m0, m1, axis, off):
    """``(indices, coefficients, constant)`` with ``a . (p1 - p0) - off = coef . q[idx] + c``,
    found by perturbing the current coordinates (restored after), or ``None`` if the map is
    not affine (a rigid body's rotation; a flexible body on a floating frame).

    The coefficients come from one-coordinate differences (+1 and -2 from the current value,
    which also test each coordinate alone); the row is then checked at :data:`JOINT_CHECKS`
    perturbations of all coordinates at once (pseudo-random, fixed seed), which a product of
    two coordinates fails.
    """
    sd = mbs.systemData
    cols = []
    for m in (m0, m1):
        got = _marker_coordinates(mbs, m)
        if got is None:
            return None
        cols += got
    cols = sorted({int(c) for c in cols})
    a = np.array(axis)

    def proj():
        return float(
            a
            @ (
                mbs.GetMarkerOutput(m1, _POSITION, _CURRENT)
                - mbs.GetMarkerOutput(m0, _POSITION, _CURRENT)
            )
        )

    q0 = sd.GetODE2Coordinates(_CURRENT)
    base = proj()
    coef = []
    try:
        for c in cols:
            for step, store in ((1.0, True), (-2.0, False)):
                q = q0.copy()
                q[c] += step
                sd.SetODE2Coordinates(q, _CURRENT)
                val = proj() - base
                if store:
                    coef.append(val)
                elif not _close(val, -2.0 * coef[-1], 1.0 + abs(coef[-1])):
                    return None
        rng = np.random.default_rng(20261128)
        for _ in range(JOINT_CHECKS if len(cols) > 1 else 0):
            dq = rng.uniform(-1.0, 1.0, len(cols))
            q = q0.copy()
            q[cols] += dq
            sd.SetODE2Coordinates(q, _CURRENT)
            want = float(np.dot(coef, dq))
            if not _close(proj() - base, want, 1.0 + float(np.abs(coef) @ np.abs(dq))):
                return None
    finally:
        sd.SetODE2Coordinates(q0, _CURRENT)
    c0 = base - float(np.dot(coef, q0[cols])) - off if cols else base - off
    return cols, coef, c0


def _close(got: float, want: float, scale: float) -> bool:
    return abs(got - want) <= 1e-9 * scale
