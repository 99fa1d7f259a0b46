"""Accepted slips of contact points on ANCF Cable2D surfaces, vectorised (post-step only).

A ``MarkerBodyPosition`` on an ``ObjectANCFCable2D`` at the local position ``(x, y)`` sits at
``p = r(x) + y n(x)``: ``r`` is the cubic Hermite interpolation of the two nodes' positions and
slopes (``Point2DSlope1``: reference plus ODE2 coordinates), ``n`` the unit normal
``(-r'_y, r'_x) / |r'|``. ``r`` and ``r'`` are linear in the coordinates, ``n`` is not, so such
points (the lap joint's contact points, with ``y`` half the lap thickness) are not affine in the
coordinates. This module evaluates ``p`` for all of them with a few numpy operations instead of
two ``GetMarkerOutput`` calls per point, and checks the formula against ``GetMarkerOutput`` at
set-up (at the current and at a perturbed configuration); markers that do not match keep the
Exudyn call.
"""

from __future__ import annotations

import exudyn as exu
import numpy as np

__all__ = ["SurfaceSlips"]

_POSITION = exu.OutputVariableType.Position
_CURRENT = exu.ConfigurationType.Current


def _hermite(xi, L):
    """Cubic Hermite weights of (r0, r0', r1, r1') and their x-derivatives at ``xi = x / L``."""
    S = [
        1 - 3 * xi**2 + 2 * xi**3,
        L * (xi - 2 * xi**2 + xi**3),
        3 * xi**2 - 2 * xi**3,
        L * (-(xi**2) + xi**3),
    ]
    dS = [
        (-6 * xi + 6 * xi**2) / L,
        1 - 4 * xi + 3 * xi**2,
        (6 * xi - 6 * xi**2) / L,
        -2 * xi + 3 * xi**2,
    ]
    return S, dS


def _cable_marker(mbs, m):
    """(ODE2 indices (8,), reference coordinates (8,), weights of x and y of r and r' (4, 8),
    y) of a MarkerBodyPosition on an ANCFCable2D with two Point2DSlope1 nodes, or None.
    """
    mk = mbs.GetMarker(m)
    if mk.get("markerType") != "BodyPosition":
        return None
    body = int(mk["bodyNumber"])
    obj = mbs.GetObject(body)
    if obj.get("objectType") != "ANCFCable2D":
        return None
    nodes = [int(n) for n in obj["nodeNumbers"]]
    if any(mbs.GetNode(n)["nodeType"] != "Point2DSlope1" for n in nodes):
        return None
    L = float(obj["length"])
    x, y = float(mk["localPosition"][0]), float(mk["localPosition"][1])
    idx = np.array(list(mbs.systemData.GetObjectLTGODE2(body)), dtype=np.intp)
    ref = np.concatenate([np.asarray(mbs.GetNode(n)["referenceCoordinates"], float) for n in nodes])
    if idx.size != 8 or ref.size != 8:
        return None
    S, dS = _hermite(x / L, L)
    W = np.zeros((4, 8))  # rows: r_x, r_y, r'_x, r'_y
    for k in range(4):  # node coordinates: [x, y, x', y'] per node
        W[0, 2 * k] = S[k]
        W[1, 2 * k + 1] = S[k]
        W[2, 2 * k] = dS[k]
        W[3, 2 * k + 1] = dS[k]
    return idx, ref, W, y


class SurfaceSlips:
    """Slips ``a . (p1 - p0) - offset`` of the points whose two markers are ANCF Cable2D
    surface markers or ground markers (constant positions).

    Attributes
    ----------
    points : ndarray of int
        The points this object computes (a subset of those asked for).
    """

    def __init__(self, mbs, pairs, candidates, axis, offsets, q):
        self.q = q
        a = np.asarray(axis, float)
        rows, points, const = [], [], []
        for i in candidates:
            m0, m1 = (int(m) for m in pairs[i])
            got = []
            for m, sgn in ((m0, -1.0), (m1, 1.0)):
                c = _cable_marker(mbs, m)
                if c is None:
                    mk = mbs.GetMarker(m)
                    body = mk.get("bodyNumber")
                    if body is None or mbs.GetObject(int(body))["objectType"] != "Ground":
                        break
                    c = float(a @ mbs.GetMarkerOutput(m, _POSITION, _CURRENT))
                got.append((c, sgn))
            else:
                points.append(i)
                const.append(-float(offsets[i]))
                rows.append(got)
        self.points = np.array(points, dtype=np.intp)
        self.c = np.array(const)
        cab = [
            (k, c, sgn) for k, got in enumerate(rows) for c, sgn in got if not isinstance(c, float)
        ]
        for k, got in enumerate(rows):
            for c, sgn in got:
                if isinstance(c, float):
                    self.c[k] += sgn * c
        self.owner = np.array([k for k, _, _ in cab], dtype=np.intp)
        self.sign = np.array([s for _, _, s in cab])
        self.idx = np.array([c[0] for _, c, _ in cab], dtype=np.intp).reshape(-1, 8)
        self.ref = np.array([c[1] for _, c, _ in cab]).reshape(-1, 8)
        W = np.array([c[2] for _, c, _ in cab]).reshape(-1, 4, 8)
        self.W = W.transpose(1, 0, 2).copy()  # (4, n_markers, 8)
        self.y = np.array([c[3] for _, c, _ in cab])
        self.ax, self.ay = float(a[0]), float(a[1])
        self.out = np.zeros(len(points))
        if len(points) and not self._matches(mbs, pairs, offsets):
            self.points = np.empty(0, dtype=np.intp)

    def slips(self) -> np.ndarray:
        """Slips of :attr:`points` [m] (a buffer reused at every call; about ten numpy calls
        whatever the number of points).
        """
        G = self.q[self.idx]
        G += self.ref
        rx, ry, tx, ty = np.einsum("mk,jmk->jm", G, self.W)
        s = self.y / np.hypot(tx, ty)
        if self.ay == 0.0:
            proj = rx - s * ty
            if self.ax != 1.0:
                proj *= self.ax
        else:
            proj = self.ax * (rx - s * ty) + self.ay * (ry + s * tx)
        proj *= self.sign
        out = self.out
        np.add(self.c, np.bincount(self.owner, proj, minlength=out.size), out=out)
        return out

    def _matches(self, mbs, pairs, offsets) -> bool:
        """The formula equals Exudyn's marker positions at the current configuration and at a
        perturbed one (restored after).
        """
        sd = mbs.systemData
        q0 = sd.GetODE2Coordinates(_CURRENT)
        a = np.array([self.ax, self.ay, 0.0])
        get = mbs.GetMarkerOutput
        ok = True
        try:
            for bump in (0.0, 1e-3):
                if bump:
                    sd.SetODE2Coordinates(q0 + bump * np.sin(np.arange(q0.size) + 1.0), _CURRENT)
                want = np.array(
                    [
                        float(
                            a
                            @ (
                                get(int(pairs[i][1]), _POSITION, _CURRENT)
                                - get(int(pairs[i][0]), _POSITION, _CURRENT)
                            )
                        )
                        - float(offsets[i])
                        for i in self.points
                    ]
                )
                got = self.slips()
                ok = ok and bool(np.all(np.abs(got - want) <= 1e-12 * (1.0 + np.abs(want))))
        finally:
            sd.SetODE2Coordinates(q0, _CURRENT)
        return ok
