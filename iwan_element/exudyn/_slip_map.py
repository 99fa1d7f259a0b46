"""Accepted slips of many marker pairs from a view of Exudyn's coordinates (post-step only).

Used by the interface and the symbolic connector route; never called in a force law.
"""
from __future__ import annotations

import exudyn as exu
import numpy as np

__all__: list[str] = []

_POSITION = exu.OutputVariableType.Position
_CURRENT = exu.ConfigurationType.Current


class SlipMap:
    """Accepted slips ``u = C q + c`` of all points from a view of the ODE2 coordinates.

    Exact for markers whose position is affine in the coordinates (node coordinates, point
    nodes, mass points, ANCF cable elements); checked at set-up with two perturbations.
    Points with other markers are read with ``GetMarkerOutput`` (post-step only).
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
        u = (self.q[self.idx] * self.coef).sum(axis=1) + self.c
        if self.generic:
            self.marker_slips(u, self.generic)
        return u

    def marker_slips(self, u: np.ndarray, points) -> None:
        """Write into ``u`` the slips of ``points`` read from Exudyn's marker positions
        (pairs with no affine row; one ``GetMarkerOutput`` per marker)."""
        a = np.asarray(self.axis, float)
        get = self.mbs.GetMarkerOutput
        for i in points:
            m0, m1 = self.pairs[i]
            u[i] = float(a @ (get(int(m1), _POSITION) - get(int(m0), _POSITION))) \
                - self.offsets[i]


def _marker_coordinates(mbs, m):
    mk = mbs.GetMarker(m)
    sd = mbs.systemData
    if "bodyNumber" in mk:
        return list(sd.GetObjectLTGODE2(int(mk["bodyNumber"])))
    if "nodeNumber" in mk:
        return list(sd.GetNodeLTGODE2(int(mk["nodeNumber"])))
    return None


def _affine_position_row(mbs, m0, m1, axis, off):
    """``(indices, coefficients, constant)`` with ``a . (p1 - p0) - off = coef . q[idx] + c``,
    found by perturbing the current coordinates (restored after), or ``None`` if the map is
    not affine (e.g. a rigid body's rotation)."""
    sd = mbs.systemData
    cols = []
    for m in (m0, m1):
        got = _marker_coordinates(mbs, m)
        if got is None:
            return None
        cols += got
    cols = sorted(set(int(c) for c in cols))
    a = np.array(axis)

    def proj():
        return float(a @ (mbs.GetMarkerOutput(m1, _POSITION, _CURRENT)
                          - mbs.GetMarkerOutput(m0, _POSITION, _CURRENT)))

    q0 = sd.GetODE2Coordinates(_CURRENT)
    base = proj()
    coef = []
    affine = True
    try:
        for c in cols:
            for step, store in ((1.0, True), (-2.0, False)):
                q = q0.copy()
                q[c] += step
                sd.SetODE2Coordinates(q, _CURRENT)
                val = proj() - base
                if store:
                    coef.append(val)
                elif abs(val + 2.0 * coef[-1]) > 1e-9 * (1.0 + abs(coef[-1])):
                    affine = False
    finally:
        sd.SetODE2Coordinates(q0, _CURRENT)
    if not affine:
        return None
    c0 = base - float(np.dot(coef, q0[cols])) - off if cols else base - off
    return cols, coef, c0


