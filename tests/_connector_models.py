"""Models and an independent reference integrator for the Exudyn connector tests.

The reference is a plain numpy Newmark integrator (average acceleration, beta = 1/4,
gamma = 1/2), which is what Exudyn's generalized-alpha method reduces to at spectral
radius 1. It solves each step's nonlinear equations with Newton's method to round-off,
using its own joint instances; it shares no code with :mod:`iwan_element.exudyn`.
"""

from __future__ import annotations

import math

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    CoordinateConstraint,
    CoordinateSpringDamper,
    LoadCoordinate,
    MarkerNodeCoordinate,
    Mass1D,
    Node1D,
    NodePointGround,
)

from iwan_element.exudyn import add_iwan_connector

SOLVERS = exu.DynamicSolverType


# ---------------------------------------------------------------------------- reference
def newmark_reference(masses, joints, *, h, n_steps, springs=(), x0=None, v0=None, force=None):
    """Newmark (beta = 1/4, gamma = 1/2) for a chain of point masses on one axis.

    Parameters
    ----------
    masses : sequence of float, shape (n,)
        Masses [kg] of the degrees of freedom ``x[0..n-1]`` [m].
    joints : sequence of (i0, i1, element)
        Joint elements between DOF ``i0`` and ``i1`` (``-1`` = ground); slip
        ``u = x[i1] - x[i0]``, the force ``F`` pulls ``i1`` back (``-F`` on ``i1``, ``+F``
        on ``i0``), as in an Exudyn coordinate spring-damper.
    springs : sequence of (i0, i1, k)
        Linear springs [N/m], same convention.
    x0, v0 : array_like, shape (n,), optional
        Initial displacements and velocities (default zero).
    force : callable ``t -> ndarray (n,)``, optional
        External forces [N].

    Returns
    -------
    t, x, v : ndarray, shapes (n_steps+1,), (n_steps+1, n), (n_steps+1, n)
    """
    M = np.asarray(masses, dtype=float)
    n = M.size
    beta, gamma = 0.25, 0.5
    x = np.zeros(n) if x0 is None else np.array(x0, dtype=float)
    v = np.zeros(n) if v0 is None else np.array(v0, dtype=float)
    ext = (lambda t: np.zeros(n)) if force is None else force

    def internal(xx):
        """Internal force vector and tangent matrix at xx (joint trials, no commit)."""
        g = np.zeros(n)
        K = np.zeros((n, n))
        for i0, i1, k in springs:
            _add(g, K, i0, i1, k * (_get(xx, i1) - _get(xx, i0)), k)
        for i0, i1, el in joints:
            F, kt = el.trial(_get(xx, i1) - _get(xx, i0))
            _add(g, K, i0, i1, F, kt)
        return g, K

    g, _ = internal(x)
    for _, _, el in joints:
        el.commit()
    a = (ext(0.0) - g) / M
    ts = [0.0]
    xs = [x.copy()]
    vs = [v.copy()]
    c0 = 1.0 / (beta * h * h)
    for step in range(1, n_steps + 1):
        t = step * h
        f = ext(t)
        xn = x + h * v + 0.5 * h * h * a  # start from the predictor
        for _ in range(60):
            an = c0 * (xn - x - h * v) - (0.5 / beta - 1.0) * a
            g, K = internal(xn)
            r = M * an + g - f
            J = np.diag(M * c0) + K
            dx = -np.linalg.solve(J, r)
            xn = xn + dx
            # converged to round-off (1e-12 of the state's scale; 1 um floor)
            if np.max(np.abs(dx)) <= 1e-12 * max(np.max(np.abs(xn)), np.max(np.abs(x)), 1e-6):
                break
        else:
            raise RuntimeError(f"reference Newton did not converge at step {step}")
        internal(xn)  # last trial at the solution
        for _, _, el in joints:
            el.commit()
        an = c0 * (xn - x - h * v) - (0.5 / beta - 1.0) * a
        v = v + h * ((1.0 - gamma) * a + gamma * an)
        a = an
        x = xn
        ts.append(t)
        xs.append(x.copy())
        vs.append(v.copy())
    return np.array(ts), np.array(xs), np.array(vs)


def _get(x, i):
    return 0.0 if i < 0 else x[i]


def _add(g, K, i0, i1, F, k):
    if i1 >= 0:
        g[i1] += F
        K[i1, i1] += k
    if i0 >= 0:
        g[i0] -= F
        K[i0, i0] += k
    if i0 >= 0 and i1 >= 0:
        K[i0, i1] -= k
        K[i1, i0] -= k


# ---------------------------------------------------------------------------- exudyn side
def settings(h, n_steps, *, rho=1.0, rel_tol=1e-12, abs_tol=1e-10, adaptive=False, tol=None):
    """Simulation settings: fixed step ``h`` (initial step if ``adaptive``), one thread."""
    sim = exu.SimulationSettings()
    ti = sim.timeIntegration
    ti.numberOfSteps = int(n_steps)
    ti.endTime = n_steps * h
    ti.verboseMode = 0
    ti.generalizedAlpha.spectralRadius = rho
    ti.newton.relativeTolerance = rel_tol
    ti.newton.absoluteTolerance = abs_tol
    ti.automaticStepSize = adaptive
    if tol is not None:
        ti.absoluteTolerance = tol
        ti.relativeTolerance = tol
    sim.solution.file.write = False
    sim.parallel.numberOfThreads = 1
    return sim


class Chain:
    """Point masses on one axis (Node1D) joined to ground and to each other."""

    def __init__(self, masses, *, x0=None, v0=None):
        self.SC = exu.SystemContainer()
        self.mbs = mbs = self.SC.AddSystem()
        n = len(masses)
        x0 = [0.0] * n if x0 is None else list(x0)
        v0 = [0.0] * n if v0 is None else list(v0)
        ground = mbs.AddNode(NodePointGround())
        self.ground_marker = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
        self.nodes = []
        self.markers = []
        for m, xi, vi in zip(masses, x0, v0):
            nd = mbs.AddNode(
                Node1D(referenceCoordinates=[0.0], initialCoordinates=[xi], initialVelocities=[vi])
            )
            mbs.AddObject(Mass1D(mass=m, nodeNumber=nd))
            self.nodes.append(nd)
            self.markers.append(mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nd, coordinate=0)))

    def marker(self, i):
        return self.ground_marker if i < 0 else self.markers[i]

    def spring(self, i0, i1, k):
        self.mbs.AddObject(
            CoordinateSpringDamper(markerNumbers=[self.marker(i0), self.marker(i1)], stiffness=k)
        )

    def joint(self, i0, i1, element, **kw):
        return add_iwan_connector(self.mbs, [self.marker(i0), self.marker(i1)], element, **kw)

    def harmonic_force(self, i, f0, omega):
        self.mbs.AddLoad(
            LoadCoordinate(
                markerNumber=self.marker(i),
                loadUserFunction=lambda mbs, t, load: f0 * math.sin(omega * t),
            )
        )

    def prescribe(self, i, motion):
        """Prescribe ``x[i](t) = motion(t)`` with a coordinate constraint to ground."""
        self.mbs.AddObject(
            CoordinateConstraint(
                markerNumbers=[self.ground_marker, self.marker(i)],
                offsetUserFunction=lambda mbs, t, itemNumber, lOffset: motion(t),
            )
        )

    def velocity(self, i):
        return self.mbs.GetNodeOutput(self.nodes[i], exu.OutputVariableType.Coordinates_t)

    def solve(self, sim, solver=SOLVERS.GeneralizedAlpha):
        self.mbs.Assemble()
        self.mbs.SolveDynamic(sim, solverType=solver)


class CommitOnTrial:
    """The classic bug, as a wrapper: commit the history inside every force evaluation."""

    def __init__(self, element):
        self.element = element

    def trial(self, u, v=0.0):
        out = self.element.trial(u, v)
        self.element.commit()
        return out

    def commit(self):
        self.element.commit()

    def revert(self):
        self.element.revert()

    def reset(self):
        self.element.reset()

    work = property(lambda self: self.element.work)
    stored_energy = property(lambda self: self.element.stored_energy)
    dissipated_energy = property(lambda self: self.element.dissipated_energy)
    displacement = property(lambda self: self.element.displacement)
    force = property(lambda self: self.element.force)
