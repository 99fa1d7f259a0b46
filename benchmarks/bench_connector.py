"""Cost of the Iwan connector in Exudyn, side by side with Exudyn's built-in linear connector.

One mass (1 kg) on a joint to ground (KT = 1e6 N/m, Fs = 1 kN, chi = -0.5, beta = 0.2),
free vibration from 3 m/s (macroslip first, then microslip), generalized-alpha with
Exudyn's default settings, fixed step 10 us, one thread, no solution file. Variants:

* ``builtin``      ObjectConnectorCoordinateSpringDamper, stiffness KT (the reference, 1.0)
* ``python-lin``   the same object with a Python user function returning ``k * deltaL``
* ``conn-linear``  :func:`add_iwan_connector` with a trivial linear element: the cost of
                   the connector machinery alone (trial-only force function, post-step
                   dispatcher, commit, records)
* ``conn-iwan``    :func:`add_iwan_connector` with :class:`IwanJoint` (records on / off)
* ``conn-discrete`` :func:`add_iwan_connector` with :class:`DiscreteIwan`, 100 sliders

Wall time is the best of ``--repeat`` runs of ``mbs.SolveDynamic`` only. Force evaluations
per step come from a separate counting run (not timed).

Run: ``python benchmarks/bench_connector.py [--steps 100000] [--repeat 3]``
"""
from __future__ import annotations

import argparse
import time

import exudyn as exu
from exudyn.itemInterface import CoordinateSpringDamper, Mass1D, MarkerNodeCoordinate, Node1D, NodePointGround

from iwan_element import DiscreteIwan, IwanJoint, IwanParameters
from iwan_element.exudyn import add_iwan_connector

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
H = 1e-5
V0 = 3.0


class LinearElement:
    """A spring KT following the element protocol, with nothing to compute: the floor."""

    def __init__(self, k):
        self.k = k
        self.displacement = self.force = self.work = self.dissipated_energy = 0.0
        self._u = 0.0

    def trial(self, u, v=0.0):
        self._u = u
        return self.k * u, self.k

    def commit(self):
        self.displacement = self._u
        self.force = self.k * self._u
        self.work = 0.5 * self.k * self._u * self._u

    stored_energy = property(lambda self: self.work)

    def revert(self):
        pass

    def reset(self):
        self.__init__(self.k)


class Counting:
    """Wraps an element and counts its trial calls (for the untimed counting run)."""

    def __init__(self, element, counter):
        self.element = element
        self.counter = counter

    def trial(self, u, v=0.0):
        self.counter[0] += 1
        return self.element.trial(u, v)

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


def build(variant, counter=None):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    node = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialVelocities=[V0]))
    mbs.AddObject(Mass1D(mass=1.0, nodeNumber=node))
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    if variant == "builtin":
        mbs.AddObject(CoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=P.KT))
    elif variant == "python-lin":
        def linear(mbs_, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
            return stiffness * deltaL
        mbs.AddObject(CoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=P.KT,
                                             springForceUserFunction=linear))
    else:
        element = {"conn-linear": lambda: LinearElement(P.KT),
                   "conn-iwan": lambda: IwanJoint(P),
                   "conn-iwan-norecord": lambda: IwanJoint(P),
                   "conn-discrete": lambda: DiscreteIwan(P, 100)}[variant]()
        if counter is not None:
            element = Counting(element, counter)
        add_iwan_connector(mbs, [m0, m1], element, record=(variant != "conn-iwan-norecord"))
    mbs.Assemble()
    return SC, mbs


def settings(steps):
    sim = exu.SimulationSettings()
    sim.timeIntegration.numberOfSteps = steps
    sim.timeIntegration.endTime = steps * H
    sim.timeIntegration.verboseMode = 0
    sim.solution.file.write = False
    sim.parallel.numberOfThreads = 1
    return sim


def run(variant, steps, repeat):
    best = float("inf")
    for _ in range(repeat):
        SC, mbs = build(variant)
        sim = settings(steps)
        t0 = time.perf_counter()
        mbs.SolveDynamic(sim)
        best = min(best, time.perf_counter() - t0)
        newton = mbs.sys["dynamicSolver"].it.newtonStepsCount / steps
    evals = float("nan")
    if variant.startswith("conn"):
        counter = [0]
        SC, mbs = build(variant, counter)
        mbs.SolveDynamic(settings(min(steps, 20000)))
        evals = counter[0] / min(steps, 20000)
    return best, newton, evals


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    variants = ["builtin", "python-lin", "conn-linear", "conn-iwan", "conn-iwan-norecord",
                "conn-discrete"]
    rows = {v: run(v, args.steps, args.repeat if v != "conn-discrete" else max(1, args.repeat - 1))
            for v in variants}
    base = rows["builtin"][0]
    print(f"one mass, {args.steps} steps, generalized-alpha (default settings), h = {H:g} s, "
          f"exudyn {exu.__version__}")
    print(f"{'variant':<20} {'wall [s]':>9} {'ratio':>7} {'us/step':>8} {'Newton it/step':>15} "
          f"{'trials/step':>12}")
    for v, (t, newton, evals) in rows.items():
        ev = "-" if evals != evals else f"{evals:.2f}"
        print(f"{v:<20} {t:9.3f} {t / base:7.1f} {1e6 * t / args.steps:8.2f} {newton:15.2f} {ev:>12}")


if __name__ == "__main__":
    main()
